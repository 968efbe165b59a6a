#include "ins_fmu_step.h"

#include <math.h>
#include <stddef.h>

#include "fmu_table.h"
#include "ins.h"

int64_t sarins_ins_fmu_io_size(void) { return SARINS_INS_IO; }

/* Two time tags name the same communication point (to tol of a step h). */
static int same_time(double a, double b, double h, double tol) { return fabs(a - b) <= tol * h; }

/* True if the drift compensation inputs (value (c, b, a), apply_from) leave the value in force of the
 * slave's Compensation state comp for the interval starting at nav_start: the pair seen last, or its
 * value again with an apply_from after every queued pair's (not queued), and no queued pair takes over. */
static int compensation_unchanged(const double *comp, const double *value, double apply_from, double nav_start,
                                  double tol)
{
    for (int i = 0; i < 3; i++)
        if (value[i] != comp[i])
            return 0; /* a new value */
    if (apply_from != comp[3] && (apply_from < nav_start - tol || !(comp[8] < apply_from - tol)))
        return 0; /* too late, or it replaces queued pairs */
    return nav_start < comp[7] - tol;
}

/* The table has the rows and shapes the step reads, and every slot indexes the buffer. */
static int table_ok(const int64_t *table, int64_t rows, int64_t n)
{
    if (rows != SARINS_INS_TABLE_ROWS)
        return 0;
    static const int64_t len[11] = {4, 3, 3, 3, 3, 1, SARINS_INS_IO, 9, SARINS_INS_ALIGN_STATES,
                                    SARINS_INS_ALIGN_STATES, SARINS_INS_ALIGN_STATES};
    for (int i = 0; i < 11; i++) {
        int64_t cols = (i == 9) ? SARINS_INS_ALIGN_STATES : 1;
        if (!sarins_table_shape(table, i, len[i], cols))
            return 0;
    }
    if (!(table[3 * 11] != 0 && table[3 * 11 + 1] >= 1 && table[3 * 11 + 2] == SARINS_INS_ALIGN_STATES))
        return 0;
    const double *io = sarins_table_row(table, 6);
    return sarins_slots_ok(io + SARINS_INS_IN, SARINS_INS_SITE - SARINS_INS_IN, n);
}

int sarins_ins_fmu_step(int64_t *table, int64_t rows, double *buf, int64_t n, double t, double h)
{
    (void)t;
    if (table == NULL || buf == NULL || !table_ok(table, rows, n))
        return 1;
    double *q = sarins_table_row(table, 0), *v = sarins_table_row(table, 1), *pos = sarins_table_row(table, 2);
    double *gyro_comp = sarins_table_row(table, 3), *accel_comp = sarins_table_row(table, 4);
    double *count = sarins_table_row(table, 5), *io = sarins_table_row(table, 6), *comp = sarins_table_row(table, 7);
    double step = io[0], tol = io[SARINS_INS_TAG_TOL];
    if (!(fabs(h - step) <= 1e-9 * step))
        return 1;
    double steps = count[0];
    double n_coarse = io[SARINS_INS_FILTER], n_align = io[3];
    if (steps < n_coarse || steps == 0 || steps == n_align - 1)
        return 1; /* coarse alignment, the first step, the end of the fine one */
    double in[SARINS_INS_N_IN];
    if (!sarins_read_slots(buf, io + SARINS_INS_IN, SARINS_INS_N_IN, in))
        return 1;
    double tag = in[6], temp_z = in[7], apply_from = in[SARINS_INS_N_IN - 1];
    if (!same_time(tag, io[1] + steps * h + h, h, tol))
        return 1; /* not the interval after the last one integrated */
    double nav_start = steps * h - io[2]; /* nav time of the interval's start */
    if (!compensation_unchanged(comp, in + 8, apply_from, nav_start, tol * h))
        return 1;
    /* the correction in force at the interval's temperature T: (a T + b) T + c */
    double correction = (comp[6] * temp_z + comp[5]) * temp_z + comp[4];
    if (!isfinite(correction))
        return 1; /* the Python step refuses it */
    int64_t hist_row = (int64_t)(steps - n_coarse);
    if (steps < n_align && !(hist_row >= 0 && hist_row < table[3 * 11 + 1]))
        return 1;
    /* every check passed: from here on the step happens */
    comp[3] = apply_from; /* the seen pair: the same value, possibly with a later apply_from */
    double row[SARINS_INS_ROW];
    if (steps < n_align) { /* fine alignment (the phase stays the same) */
        double *hist = sarins_table_row(table, 11) + SARINS_INS_ALIGN_STATES * hist_row;
        sarins_ins_align_steps(1, q, v, pos, in, in + 3, step, gyro_comp, accel_comp, sarins_table_row(table, 8),
                               sarins_table_row(table, 9), sarins_table_row(table, 10), io[SARINS_INS_FILTER + 1],
                               hist);
        sarins_ins_held_row(q, pos, row);
    } else {
        sarins_ins_nav_steps(1, q, v, pos, in, in + 3, step, gyro_comp, accel_comp, &correction, row);
    }
    count[0] = steps + 1;
    for (int i = 0; i < SARINS_INS_ROW; i++)
        buf[(int64_t)io[SARINS_INS_NAV + i]] = row[i];
    /* position error wrt the known start: north = dL (R_M + h0), east = dlambda (R_N + h0) cos L0 */
    double dlat = row[0] - io[SARINS_INS_SITE];
    double dlon = row[1] - io[SARINS_INS_SITE + 1];
    double north = dlat * io[SARINS_INS_SITE + 2];
    double east = dlon * io[SARINS_INS_SITE + 3] * io[SARINS_INS_SITE + 4];
    double err[5] = {dlat, dlon, north, east, hypot(north, east)};
    for (int i = 0; i < 5; i++)
        buf[(int64_t)io[SARINS_INS_ERR + i]] = err[i];
    double est[4] = {gyro_comp[0], gyro_comp[1], accel_comp[0], accel_comp[1]};
    for (int i = 0; i < 4; i++)
        buf[(int64_t)io[SARINS_INS_EST + i]] = est[i];
    double nav_time = (steps + 1) * step - io[2];
    buf[(int64_t)io[SARINS_INS_TEMP]] = nav_time;
    buf[(int64_t)io[SARINS_INS_TEMP + 1]] = temp_z;
    if (steps + 1 < n_align || fabs(nav_time) < 0.5 * step) {
        buf[(int64_t)io[SARINS_INS_TEMP + 3]] = temp_z;
        buf[(int64_t)io[SARINS_INS_TEMP + 4]] = temp_z - buf[(int64_t)io[SARINS_INS_TEMP + 2]];
    }
    buf[(int64_t)io[SARINS_INS_TEMP + 5]] = io[1] + (steps + 1) * step; /* solution_time */
    return 0;
}
