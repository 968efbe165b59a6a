/* Array tables: how a compiled FMU step reaches the state its slave keeps.
 *
 * A table is rows x 3 int64: (address of a C-contiguous float64 array,
 * shape[0], shape[1] or 1), built by sarins_fmu._jit.array_table from arrays
 * the Python objects own and update in place only.  The steps read their
 * inputs from, and write their outputs to, the slave's float64 Real buffer
 * at slots stored (as doubles) in an io row of the table.
 */
#ifndef SARINS_FMU_TABLE_H
#define SARINS_FMU_TABLE_H

#include "smath.h"
#include <stdint.h>

/* Row i of a table as a double pointer. */
static inline double *sarins_table_row(const int64_t *table, int64_t i)
{
    return (double *)(uintptr_t)table[3 * i];
}

/* True if row i holds exactly n0 x n1 values. */
static inline int sarins_table_shape(const int64_t *table, int64_t i, int64_t n0, int64_t n1)
{
    return table[3 * i] != 0 && table[3 * i + 1] == n0 && table[3 * i + 2] == n1;
}

/* True if every one of the count slots is an integer index into a buffer of n values. */
static inline int sarins_slots_ok(const double *slots, int64_t count, int64_t n)
{
    for (int64_t i = 0; i < count; i++)
        if (!(slots[i] >= 0.0 && slots[i] < (double)n && slots[i] == sm_floor(slots[i])))
            return 0;
    return 1;
}

/* out[i] = buf[slots[i]]; 0 if a value is not finite. */
static inline int sarins_read_slots(const double *buf, const double *slots, int64_t count, double *out)
{
    for (int64_t i = 0; i < count; i++) {
        out[i] = buf[(int64_t)slots[i]];
        if (!isfinite(out[i]))
            return 0;
    }
    return 1;
}

#endif
