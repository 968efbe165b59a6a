/* IMULog FMU (native): plays a recorded IMU log in the project's CSV format 1 (docs/imu-log.md) as
 * increments, e.g. into StrapdownINS.
 *
 * The declaration (variables, descriptions, the timing contract) is fmus/imu_log_slave.py.  At
 * initialisation the whole file is read into one buffer (at most MAX_LOG_BYTES), checked with the grammar
 * and rules of sarins_fmu.imu_log (tag line, '# key: value' metadata, the header, one kind of line end,
 * n_cols - 1 commas per line, strictly uniform clock within 1e-6 h, first sample in [0, h], finite values,
 * the full-scale and mean-gravity unit checks) and its numbers parsed into one table allocated once: the
 * core's block parser (log_parse.h: decimals of up to 19 significant digits, correctly rounded) where it takes
 * the lines, else strtod, which glibc rounds correctly: every number is the double Python's float() gives, so the outputs equal the
 * in-process reader's bit for bit (rates become increments as rate * h there and here).  Other formats (NPZ,
 * gzip, vendor CSV, i2Nav, ROS) are refused naming the conversion.  do_step only indexes the table.
 * Units: rad, m/s, degC, s; lat_deg, lon_deg in deg, height_m in m.
 */
#include "smath.h"

#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "log_parse.h"
#include "model.h"
#include "variables.h"

#define MAX_LOG_BYTES (2LL * 1024 * 1024 * 1024) /* sarins_fmu.imu_log.MAX_LOG_BYTES */
#define MAX_META_LINE 1024                       /* bytes of one metadata line */
#define MAX_META_KEYS 64
#define MAX_DATA_LINE 4096 /* bytes of one header or sample line */
#define MAX_COLS 64        /* a header naming more columns names unknown ones */
#define STRICT_TOL 1e-6    /* of h: every time step */
#define START_TOL 1e-6     /* of h: the first time_s lies in [0, h] */
#define MAX_GYRO_RATE 35.0 /* rad/s, sarins_fmu.imu_log_checks */
#define MAX_FORCE (16 * 9.80665)
#define GRAVITY_MIN 9.0
#define GRAVITY_MAX 10.6
#define DEG (3.141592653589793 / 180.0) /* Python's math.radians factor */
#define RAD (180.0 / 3.141592653589793) /* math.degrees */
#define TAG "# sarins-imu-log 1"
#define CONVERT "write it as the project's CSV log format 1 (docs/imu-log.md: in Python, " \
                "sarins_fmu.imu_log.write_log(PATH.csv, ...) of read_log(file))"

static const char *const COLS_INC[6] = {"dtheta_x_rad", "dtheta_y_rad", "dtheta_z_rad",
                                        "dv_x_mps", "dv_y_mps", "dv_z_mps"};
static const char *const COLS_RATE[6] = {"gyro_x_radps", "gyro_y_radps", "gyro_z_radps",
                                         "accel_x_mps2", "accel_y_mps2", "accel_z_mps2"};
static const char *const COLS_TEMP[6] = {"temp_gyro_x_c", "temp_gyro_y_c", "temp_gyro_z_c",
                                         "temp_accel_x_c", "temp_accel_y_c", "temp_accel_z_c"};
static const char *const COLS_REF[3] = {"ref_lat_deg", "ref_lon_deg", "ref_height_m"};
static const char *const WRONG_UNITS[9] = {"_deg", "_dps", "_degps", "_g", "_mg", "_ug", "_f", "_k", NULL};

/* What changes during a run (plain data: the FMU state copies it). */
typedef struct {
    int64_t next;   /* index of the sample the next step publishes (0 .. n) */
    double step;    /* s, the communication step, fixed by the first doStep */
    int have_step;
} il_state;

/* The log, read at initialisation (a function of log_file only: not part of the FMU state). */
typedef struct {
    double *table;  /* n rows of n_cols numbers, as written */
    int64_t n;
    int n_cols, col_time, col_imu[6], col_temp[6]; /* col_temp[0] < 0: no temperatures */
    int rates;      /* 1: the IMU columns are rates (increment = rate * h) */
    double h, lat_deg, lon_deg, height_m;
} il_work;

/* 1 when the state fits the log (a state set by the host is checked before it is used). */
static int il_state_ok(const il_state *st, const il_work *w)
{
    return st->next >= 0 && st->next <= w->n && (st->have_step == 0 || st->have_step == 1) &&
           (!st->have_step || (st->step > 0 && st->step <= 1e300));
}

static void il_release(sarins_ctx *c)
{
    il_work *w = c->work;
    if (w != NULL)
        free(w->table);
    free(w);
    c->work = NULL;
}

static int ends_with(const char *s, const char *suffix)
{
    size_t a = strlen(s), b = strlen(suffix);
    return a >= b && strcmp(s + a - b, suffix) == 0;
}

static int is_space(char ch)
{
    return ch == ' ' || ch == '\t' || ch == '\f' || ch == '\v';
}

/* 1 when s[0..len) is nan, inf or infinity (any case), as Python's float() reads them. */
static int is_special(const char *s, size_t len)
{
    static const char *const WORDS[3] = {"nan", "inf", "infinity"};
    for (int k = 0; k < 3; k++) {
        size_t n = strlen(WORDS[k]), i = 0;
        while (i < n && i < len && (s[i] | 0x20) == WORDS[k][i])
            i++;
        if (i == n && n == len)
            return 1;
    }
    return 0;
}

/* A number in Python float()'s decimal form ([+-]digits[.digits][e[+-]digits], blanks around); 1 and *out. */
static int parse_number(const char *s, size_t len, double *out)
{
    char buf[MAX_DATA_LINE + 1];
    size_t i = 0, j;
    while (i < len && is_space(s[i]))
        i++;
    while (len > i && is_space(s[len - 1]))
        len--;
    if (len - i == 0 || len - i > MAX_DATA_LINE)
        return 0;
    j = i;
    if (s[j] == '+' || s[j] == '-')
        j++;
    if (is_special(s + j, len - j))
        goto convert; /* nan, inf, infinity: read, then refused as non-finite like Python's */
    size_t digits = 0;
    while (j < len && s[j] >= '0' && s[j] <= '9')
        j++, digits++;
    if (j < len && s[j] == '.') {
        j++;
        while (j < len && s[j] >= '0' && s[j] <= '9')
            j++, digits++;
    }
    if (digits == 0)
        return 0;
    if (j < len && (s[j] == 'e' || s[j] == 'E')) {
        j++;
        if (j < len && (s[j] == '+' || s[j] == '-'))
            j++;
        size_t exp_digits = 0;
        while (j < len && s[j] >= '0' && s[j] <= '9')
            j++, exp_digits++;
        if (exp_digits == 0)
            return 0;
    }
    if (j != len)
        return 0;
convert:
    memcpy(buf, s + i, len - i);
    buf[len - i] = '\0';
    char *end = NULL;
    *out = strtod(buf, &end); /* correctly rounded (glibc); overflow gives inf, refused as non-finite */
    return end == buf + (len - i);
}

/* The whole file into a new buffer (*size bytes, NUL-terminated); NULL with a logged reason. */
static char *read_file(sarins_ctx *c, const char *path, int64_t *size)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: no such log file (or it cannot be opened)", path);
        return NULL;
    }
    long n = -1;
    if (fseek(f, 0, SEEK_END) == 0)
        n = ftell(f);
    if (n < 0 || fseek(f, 0, SEEK_SET) != 0) {
        fclose(f);
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: not a regular file of at most 2 GiB (a folder or ROS bag?); %s", path,
                   CONVERT);
        return NULL;
    }
#if LONG_MAX > 2147483647L /* a 32-bit long (win64) measures no file over 2 GiB: ftell fails above */
    if (n > MAX_LOG_BYTES) {
        fclose(f);
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: %lld bytes, more than an IMU log's budget "
                   "(MAX_LOG_BYTES = %lld)", path, (long long)n, MAX_LOG_BYTES);
        return NULL;
    }
#endif
    char *buf = malloc((size_t)n + 1);
    if (buf == NULL) {
        fclose(f);
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: out of memory for %lld bytes", path, (long long)n);
        return NULL;
    }
    size_t got = n > 0 ? fread(buf, 1, (size_t)n, f) : 0;
    int bad = ferror(f);
    fclose(f);
    if (bad || got != (size_t)n) {
        free(buf);
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: read error (a folder or ROS bag?); %s", path, CONVERT);
        return NULL;
    }
    buf[n] = '\0';
    *size = n;
    return buf;
}

/* Refuse the formats the FMU does not read, naming the conversion; SARINS_OK for a tagged CSV log. */
static int check_format(sarins_ctx *c, const char *path, const char *buf, int64_t size)
{
    const char *kind = NULL;
    if (ends_with(path, ".npz") || (size >= 2 && buf[0] == 'P' && buf[1] == 'K'))
        kind = "an NPZ log";
    else if (ends_with(path, ".gz") || (size >= 2 && (unsigned char)buf[0] == 0x1f && (unsigned char)buf[1] == 0x8b))
        kind = "a gzip file";
    else if (ends_with(path, ".bag") || ends_with(path, ".db3") || ends_with(path, ".mcap"))
        kind = "a ROS bag";
    else if (size >= (int64_t)strlen(TAG) && strncmp(buf, TAG, strlen(TAG)) == 0)
        return SARINS_OK;
    else if (size > 0 && ((buf[0] >= '0' && buf[0] <= '9') || buf[0] == '-' || buf[0] == '+' || buf[0] == '.'))
        kind = "a text log of numbers without the tag line (i2Nav / KF-GINS?)";
    else
        kind = "a CSV file without the line '" TAG "' (a vendor CSV?)";
    sarins_log(c, SARINS_ERROR, "parameter log_file: %s: %s; this FMU reads only the project's CSV log format 1: %s",
               path, kind, CONVERT);
    return SARINS_ERROR;
}

/* Line `number` of the head at buf[*pos]: its span without the line end; -1 and a message if bad. */
static int next_line(sarins_ctx *c, const char *path, const char *buf, int64_t size, int64_t *pos, int number,
                     int *crlf, int64_t *start, int64_t *len, int64_t max_len)
{
    int64_t s = *pos, e = s;
    while (e < size && buf[e] != '\n')
        e++;
    int64_t end = e;
    int cr = e > s && e < size && buf[e - 1] == '\r';
    if (e < size) {
        if (*crlf < 0)
            *crlf = cr;
        else if (cr != *crlf) {
            sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: line ends in %s, the lines before in %s; "
                       "use one kind of line end", path, number, cr ? "CRLF" : "LF", *crlf ? "CRLF" : "LF");
            return -1;
        }
        end = e - cr;
    }
    if (end - s > max_len) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: longer than %lld characters", path, number,
                   (long long)max_len);
        return -1;
    }
    if (memchr(buf + s, '\r', (size_t)(end - s)) != NULL || memchr(buf + s, '\0', (size_t)(end - s)) != NULL) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: a carriage return or NUL inside the line",
                   path, number);
        return -1;
    }
    *start = s;
    *len = end - s;
    *pos = e < size ? e + 1 : size;
    return 0;
}

static int known_column(const char *name)
{
    if (strcmp(name, "time_s") == 0)
        return 1;
    for (int k = 0; k < 6; k++)
        if (!strcmp(name, COLS_INC[k]) || !strcmp(name, COLS_RATE[k]) || !strcmp(name, COLS_TEMP[k]))
            return 1;
    for (int k = 0; k < 3; k++)
        if (!strcmp(name, COLS_REF[k]))
            return 1;
    return 0;
}

static int find_column(char names[][MAX_DATA_LINE + 1], int n, const char *name)
{
    for (int j = 0; j < n; j++)
        if (strcmp(names[j], name) == 0)
            return j;
    return -1;
}

/* Header and column plan (sarins_fmu.imu_log._check_header, _sarins_columns). */
static int plan_columns(sarins_ctx *c, const char *path, const char *line, int64_t len, int number, il_work *w)
{
    char(*names)[MAX_DATA_LINE + 1] = malloc(MAX_COLS * sizeof *names);
    if (names == NULL) {
        sarins_log(c, SARINS_ERROR, "out of memory for the log's header");
        return SARINS_ERROR;
    }
    int n = 0, code = SARINS_ERROR;
    int64_t s = 0;
    for (;;) {
        int64_t e = s;
        while (e < len && line[e] != ',')
            e++;
        if (n == MAX_COLS) {
            sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: more than %d columns", path, number,
                       MAX_COLS);
            goto done;
        }
        int64_t a = s, b = e;
        while (a < b && is_space(line[a]))
            a++;
        while (b > a && is_space(line[b - 1]))
            b--;
        memcpy(names[n], line + a, (size_t)(b - a));
        names[n][b - a] = '\0';
        n++;
        if (e >= len)
            break;
        s = e + 1;
    }
    for (int j = 0; j < n; j++) {
        if (find_column(names, j, names[j]) >= 0) {
            sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: column %s appears twice", path, number,
                       names[j]);
            goto done;
        }
        for (int k = 0; WRONG_UNITS[k] != NULL; k++)
            if (ends_with(names[j], WRONG_UNITS[k]) && strncmp(names[j], "ref_", 4) != 0) {
                sarins_log(c, SARINS_ERROR, "parameter log_file: %s: column '%s': the log takes SI units; convert it",
                           path, names[j]);
                goto done;
            }
        if (!known_column(names[j])) {
            sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: column '%.40s' is not a log column", path,
                       number, names[j]);
            goto done;
        }
    }
    w->n_cols = n;
    w->col_time = find_column(names, n, "time_s");
    if (w->col_time < 0) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: no time_s column", path);
        goto done;
    }
    int n_inc = 0, n_rate = 0, n_temp = 0, n_ref = 0;
    for (int k = 0; k < 6; k++) {
        n_inc += find_column(names, n, COLS_INC[k]) >= 0;
        n_rate += find_column(names, n, COLS_RATE[k]) >= 0;
        n_temp += find_column(names, n, COLS_TEMP[k]) >= 0;
    }
    for (int k = 0; k < 3; k++)
        n_ref += find_column(names, n, COLS_REF[k]) >= 0;
    if (n_inc && n_rate) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: give increments (dtheta_/dv_ columns) or rates "
                   "(gyro_/accel_ columns), not both", path);
        goto done;
    }
    if (n_inc != 6 && n_rate != 6) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: needs the columns dtheta_x_rad, dtheta_y_rad, "
                   "dtheta_z_rad, dv_x_mps, dv_y_mps, dv_z_mps or gyro_x_radps, gyro_y_radps, gyro_z_radps, "
                   "accel_x_mps2, accel_y_mps2, accel_z_mps2", path);
        goto done;
    }
    if (n_temp != 0 && n_temp != 6) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: give all six temperature columns or none", path);
        goto done;
    }
    if (n_ref != 0 && n_ref != 3) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: give all of ref_lat_deg, ref_lon_deg, ref_height_m "
                   "or none", path);
        goto done;
    }
    w->rates = n_rate == 6;
    for (int k = 0; k < 6; k++) {
        w->col_imu[k] = find_column(names, n, w->rates ? COLS_RATE[k] : COLS_INC[k]);
        w->col_temp[k] = n_temp ? find_column(names, n, COLS_TEMP[k]) : -1;
    }
    code = SARINS_OK;
done:
    free(names);
    return code;
}

/* '# key: value' metadata; lat_deg, lon_deg, height_m taken. */
static int meta_line(sarins_ctx *c, const char *path, const char *line, int64_t len, int number, int *have,
                     double *values)
{
    static const char *const KEYS[3] = {"lat_deg", "lon_deg", "height_m"};
    int64_t i = 1, k0, k1;
    while (i < len && is_space(line[i]))
        i++;
    k0 = i;
    while (i < len && line[i] != ':')
        i++;
    k1 = i;
    while (k1 > k0 && is_space(line[k1 - 1]))
        k1--;
    int ok = i < len && k1 > k0 && !(line[k0] >= '0' && line[k0] <= '9');
    for (int64_t j = k0; ok && j < k1; j++) {
        char ch = line[j];
        ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') || ch == '_';
    }
    if (!ok) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: metadata must read '# key: value' (key: "
                   "letters, digits, '_')", path, number);
        return SARINS_ERROR;
    }
    for (int k = 0; k < 3; k++) {
        if ((size_t)(k1 - k0) != strlen(KEYS[k]) || strncmp(line + k0, KEYS[k], (size_t)(k1 - k0)) != 0)
            continue;
        if (have[k]) {
            sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: metadata %s given twice", path, number,
                       KEYS[k]);
            return SARINS_ERROR;
        }
        have[k] = 1;
        if (!parse_number(line + i + 1, (size_t)(len - i - 1), &values[k])) {
            sarins_log(c, SARINS_ERROR, "parameter log_file: %s: lat_deg, lon_deg and height_m must be numbers",
                       path);
            return SARINS_ERROR;
        }
    }
    return SARINS_OK;
}

/* The sample lines in buf[0..len) into w->table (cap rows), line by line (the block parser did not take them). */
static int64_t parse_lines(sarins_ctx *c, const char *path, const char *buf, int64_t len, int crlf,
                           int first_line, il_work *w, int64_t cap)
{
    int64_t pos = 0, rows = 0;
    int number = first_line;
    while (pos < len) {
        int64_t s, n;
        if (next_line(c, path, buf, len, &pos, number, &crlf, &s, &n, MAX_DATA_LINE) < 0)
            return -1;
        const char *line = buf + s;
        if (n == 0 || line[0] == '#') {
            sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: %s (the log has none after the header)",
                       path, number, n == 0 ? "blank line" : "'#' line");
            return -1;
        }
        if (rows >= cap)
            return -1; /* cannot happen: cap counts the lines */
        int64_t f = 0;
        for (int j = 0; j < w->n_cols; j++) {
            int64_t e = f;
            while (e < n && line[e] != ',')
                e++;
            if ((j < w->n_cols - 1) != (e < n)) {
                sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: not %d comma-separated columns as the "
                           "header", path, number, w->n_cols);
                return -1;
            }
            if (!parse_number(line + f, (size_t)(e - f), &w->table[rows * w->n_cols + j])) {
                sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: column %d: '%.*s' is not a number",
                           path, number, j + 1, (int)(e - f < 40 ? e - f : 40), line + f);
                return -1;
            }
            f = e + 1;
        }
        rows++;
        number++;
    }
    return rows;
}

/* The clock, finite values and unit checks of the table (sarins_fmu.imu_log_stream.LogBuilder). */
static int check_samples(sarins_ctx *c, const char *path, il_work *w, int line0)
{
    const double *t = w->table;
    int nc = w->n_cols;
    for (int64_t i = 0; i < w->n; i++)
        for (int j = 0; j < nc; j++)
            if (!(sm_fabs(t[i * nc + j]) <= 1.7976931348623157e308)) {
                sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %lld: column %d is NaN or infinite", path,
                           (long long)(line0 + i), j + 1);
                return SARINS_ERROR;
            }
    if (w->n < 2) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: a log needs at least two samples", path);
        return SARINS_ERROR;
    }
    int ct = w->col_time;
    double h = t[nc + ct] - t[ct];
    w->h = h;
    if (h > 0 && !(t[ct] >= -START_TOL * h && t[ct] <= h + START_TOL * h)) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: the first timestamp is %.10g s; time_s counts "
                   "from the start of the recording, so the first sample lies in [0, h] = [0, %.9g] s", path, line0,
                   t[ct], h);
        return SARINS_ERROR;
    }
    double force_sum = 0.0;
    for (int64_t i = 0; i < w->n; i++) {
        if (i > 0) {
            double dt = t[i * nc + ct] - t[(i - 1) * nc + ct];
            if (dt <= 0) {
                sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %lld: timestamp %.10g s is %s", path,
                           (long long)(line0 + i), t[i * nc + ct],
                           dt == 0 ? "duplicated" : "earlier than the one before (non-monotonic)");
                return SARINS_ERROR;
            }
            if (sm_fabs(dt - h) > STRICT_TOL * h) {
                sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %lld: time step %.9g s differs from the "
                           "log's %.9g s (%s); logs must be uniformly sampled", path, (long long)(line0 + i), dt, h,
                           dt > 1.5 * h ? "a gap" : "a rate change");
                return SARINS_ERROR;
            }
        }
        double v[6];
        for (int k = 0; k < 6; k++)
            v[k] = w->rates ? t[i * nc + w->col_imu[k]] : t[i * nc + w->col_imu[k]] / h;
        double gyro = sm_sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        double force = sm_sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5]);
        if (gyro > MAX_GYRO_RATE || force > MAX_FORCE) {
            sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %lld: %s %.4g is beyond any IMU (%g rad/s, "
                       "%.4g m/s^2): degrees logged as radians, or rates logged as increments or the reverse?", path,
                       (long long)(line0 + i), gyro > MAX_GYRO_RATE ? "angular rate [rad/s]" :
                       "specific force [m/s^2]", gyro > MAX_GYRO_RATE ? gyro : force, MAX_GYRO_RATE, MAX_FORCE);
            return SARINS_ERROR;
        }
        force_sum += force;
    }
    double g_mean = force_sum / (double)w->n;
    if (!(g_mean >= GRAVITY_MIN && g_mean <= GRAVITY_MAX)) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: mean specific force %.4g m/s^2 over the log is not "
                   "gravity (accelerations in g, or rates logged as increments or the reverse?)", path, g_mean);
        return SARINS_ERROR;
    }
    return SARINS_OK;
}

/* Read and check the log named by log_file into w; SARINS_ERROR with a logged reason. */
static int load(sarins_ctx *c, il_work *w)
{
    const char *path = c->s[SARINS_S_log_file];
    if (path[0] == '\0') {
        sarins_log(c, SARINS_ERROR, "parameter log_file is empty: give the path of an IMU log");
        return SARINS_ERROR;
    }
    int64_t size = 0;
    char *buf = read_file(c, path, &size);
    if (buf == NULL)
        return SARINS_ERROR;
    int code = SARINS_ERROR, crlf = -1, have[3] = {0, 0, 0}, n_meta = 0, number = 1;
    double site[3] = {0.0, 0.0, 0.0};
    int64_t pos = 0, s, n;
    if (check_format(c, path, buf, size) != SARINS_OK)
        goto done;
    for (;; number++) {
        if (pos >= size || number > MAX_META_KEYS + 2) {
            sarins_log(c, SARINS_ERROR, "parameter log_file: %s: no column header line", path);
            goto done;
        }
        int64_t limit = buf[pos] == '#' ? MAX_META_LINE : MAX_DATA_LINE;
        if (next_line(c, path, buf, size, &pos, number, &crlf, &s, &n, limit) < 0)
            goto done;
        const char *line = buf + s;
        int blank = 1;
        for (int64_t j = 0; j < n && blank; j++)
            blank = is_space(line[j]);
        if (blank) {
            sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: blank line (the log has none: metadata, "
                       "header, samples)", path, number);
            goto done;
        }
        if (number == 1) {
            if ((size_t)n != strlen(TAG) || strncmp(line, TAG, (size_t)n) != 0) {
                sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line 1 must be '%s', got '%.60s'", path, TAG,
                           line);
                goto done;
            }
            continue;
        }
        if (line[0] != '#') {
            if (plan_columns(c, path, line, n, number, w) != SARINS_OK)
                goto done;
            break;
        }
        if (n_meta >= MAX_META_KEYS) {
            sarins_log(c, SARINS_ERROR, "parameter log_file: %s: line %d: more than %d metadata lines", path, number,
                       MAX_META_KEYS);
            goto done;
        }
        n_meta++;
        if (meta_line(c, path, line, n, number, have, site) != SARINS_OK)
            goto done;
    }
    if (pos >= size) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: no samples after the header (line %d)", path, number);
        goto done;
    }
    if (!have[0]) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: metadata lat_deg (static start latitude, deg) is "
                   "required", path);
        goto done;
    }
    if (!(sm_fabs(site[1]) <= 1.7976931348623157e308 && sm_fabs(site[2]) <= 1.7976931348623157e308 &&
          sm_fabs(site[0]) <= 89.9)) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: lat_deg %.17g must be finite and within +-89.9 deg",
                   path, site[0]);
        goto done;
    }
    int64_t lines = 1; /* the last line may lack its end */
    for (int64_t j = pos; j < size; j++)
        lines += buf[j] == '\n';
    w->table = malloc((size_t)lines * (size_t)w->n_cols * sizeof(double));
    if (w->table == NULL) {
        sarins_log(c, SARINS_ERROR, "parameter log_file: %s: out of memory for %lld samples", path, (long long)lines);
        goto done;
    }
    int64_t rows = crlf < 0 ? SARINS_LOG_NOT_TAKEN :
        sarins_log_parse_block(buf + pos, size - pos, w->n_cols, crlf, MAX_DATA_LINE, w->table, lines);
    if (rows == SARINS_LOG_NOT_TAKEN)
        rows = parse_lines(c, path, buf + pos, size - pos, crlf < 0 ? 0 : crlf, number + 1, w, lines);
    if (rows < 0)
        goto done;
    w->n = rows;
    if (check_samples(c, path, w, number + 1) != SARINS_OK)
        goto done;
    w->lat_deg = (site[0] * DEG) * RAD;
    w->lon_deg = (site[1] * DEG) * RAD;
    w->height_m = site[2];
    code = SARINS_OK;
done:
    free(buf);
    return code;
}

/* Outputs of sample k (the increments over its interval, its temperatures and time). */
static void publish(sarins_ctx *c, const il_work *w, int64_t k)
{
    const double *row = w->table + k * w->n_cols;
    double *r = c->r;
    static const int IMU[6] = {SARINS_R_dtheta_x, SARINS_R_dtheta_y, SARINS_R_dtheta_z,
                               SARINS_R_dv_x, SARINS_R_dv_y, SARINS_R_dv_z};
    for (int j = 0; j < 6; j++)
        r[IMU[j]] = w->rates ? row[w->col_imu[j]] * w->h : row[w->col_imu[j]];
    r[SARINS_R_log_time] = row[w->col_time];
}

static void publish_temps(sarins_ctx *c, const il_work *w, int64_t k)
{
    static const int TEMP[6] = {SARINS_R_temp_gyro_x, SARINS_R_temp_gyro_y, SARINS_R_temp_gyro_z,
                                SARINS_R_temp_accel_x, SARINS_R_temp_accel_y, SARINS_R_temp_accel_z};
    if (w->col_temp[0] < 0)
        return;
    for (int j = 0; j < 6; j++)
        c->r[TEMP[j]] = w->table[k * w->n_cols + w->col_temp[j]];
}

static int il_initialize(sarins_ctx *c)
{
    il_work *w = calloc(1, sizeof *w);
    if (w == NULL) {
        sarins_log(c, SARINS_ERROR, "out of memory for the log");
        return SARINS_ERROR;
    }
    if (load(c, w) != SARINS_OK) {
        free(w->table);
        free(w);
        return SARINS_ERROR;
    }
    c->work = w;
    il_state *st = c->state;
    memset(st, 0, sizeof *st);
    double *r = c->r;
    r[SARINS_R_log_step] = w->h;
    r[SARINS_R_log_time] = w->table[w->col_time] - w->h;
    r[SARINS_R_lat_deg] = w->lat_deg;
    r[SARINS_R_lon_deg] = w->lon_deg;
    r[SARINS_R_height_m] = w->height_m;
    publish_temps(c, w, 0);
    return SARINS_OK;
}

static int il_do_step(sarins_ctx *c, double t, double h)
{
    il_work *w = c->work;
    il_state *st = c->state;
    if (!il_state_ok(st, w)) { /* a state set by the host that does not fit this log */
        sarins_log(c, SARINS_ERROR, "the FMU state does not fit the log (sample index %lld of %lld)",
                   (long long)st->next, (long long)w->n);
        return SARINS_ERROR;
    }
    if (st->have_step && sm_fabs(h - st->step) > 1e-9 * st->step) {
        sarins_log(c, SARINS_ERROR, "ValueError: communication step changed from %.17g s to %.17g s; this FMU needs "
                   "a fixed step", st->step, h);
        return SARINS_ERROR;
    }
    st->step = h;
    st->have_step = 1;
    if (sm_fabs(h - w->h) > 1e-9 * w->h) {
        sarins_log(c, SARINS_ERROR, "ValueError: communication step %.17g s differs from the log's interval %.17g s",
                   h, w->h);
        return SARINS_ERROR;
    }
    double q = sm_nearbyint(t / h); /* Python's round(): halfway cases to even */
    if (sm_fabs(q * h - t) > 1e-6 * h || q < 0) {
        sarins_log(c, SARINS_ERROR, "ValueError: time %.17g s is not on the log's %.17g s grid", t, w->h);
        return SARINS_ERROR;
    }
    if (q >= (double)w->n) {
        sarins_log(c, SARINS_ERROR, "ValueError: the log ends at FMU time %.9g s", (double)w->n * w->h);
        return SARINS_ERROR;
    }
    int64_t k = (int64_t)q;
    publish(c, w, k);
    publish_temps(c, w, k);
    c->r[SARINS_R_increment_end_time] = (double)(k + 1) * h;
    st->next = k + 1;
    return SARINS_OK;
}

/* A state handed to the FMU (model.h "State validation"): what the state alone must satisfy; the sample
 * index against the log's length is checked by il_state_ok before each step. */
static int il_check_state(const sarins_ctx *c, int running)
{
    (void)running;
    const il_state *st = c->state;
    int ok = sarins_state_int(c, "next", st->next, 0, 1LL << 53) &&
             sarins_state_int(c, "have_step", st->have_step, 0, 1) &&
             (st->have_step ? sarins_state_real(c, "step", st->step, 1e-300, 1e300)
                            : sarins_state_real(c, "step", st->step, 0.0, 0.0));
    return ok ? SARINS_OK : SARINS_ERROR;
}

const sarins_model sarins_model_desc = {
    .table = &SARINS_TABLE,
    .state_size = sizeof(il_state),
    .state_version = 1,
    .initialize = il_initialize,
    .do_step = il_do_step,
    .release = il_release,
    .check_state = il_check_state,
};
