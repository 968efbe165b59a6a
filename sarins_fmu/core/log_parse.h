/* log_parse: the sample lines of a text IMU log (CSV) parsed into doubles, for sarins_fmu.imu_log.
 *
 * A block of whole lines (each ending in its line end, LF or CRLF, except possibly the file's last) is checked
 * against the log's line grammar (one kind of line end, no carriage return inside a line, no line longer than
 * max_line, no blank or '#' line, n_cols - 1 commas on every line) and each field is converted to a double.
 * A field is taken only in the form [blanks][+-]digits[.digits][(e|E)[+-]digits][blanks] (or .digits) with at
 * most 15 significant digits and a decimal exponent that keeps the value an exact decimal integer times an
 * exact power of ten within 10^22: then one IEEE multiplication or division gives the correctly rounded double
 * (Clinger's fast path), bit-identical to Python's float().  Anything else (another number form, a grammar
 * error, a full buffer) makes the function return SARINS_LOG_NOT_TAKEN and the caller parses the block its
 * own way (which also words the error).  No allocation; reentrant.
 */
#ifndef SARINS_LOG_PARSE_H
#define SARINS_LOG_PARSE_H

#include <stdint.h>

#define SARINS_LOG_NOT_TAKEN (-1)

/* Parse buf[0..len) into out (row-major, cap_rows x n_cols doubles).  crlf: 1 when the file's lines end in
 * CRLF, 0 for LF.  Returns the number of rows, or SARINS_LOG_NOT_TAKEN. */
int64_t sarins_log_parse_block(const char *buf, int64_t len, int32_t n_cols, int32_t crlf, int32_t max_line,
                               double *out, int64_t cap_rows);

#endif
