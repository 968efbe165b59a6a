#include "turntable_fmu_step.h"

#include <math.h>
#include <stddef.h>

#include "fmu_table.h"
#include "turntable.h"

/* The table has the rows and shapes the step reads, and every slot it writes indexes the buffer. */
static int table_ok(const int64_t *table, int64_t rows, int64_t n)
{
    if (rows != SARINS_TT_TABLE_ROWS || !sarins_table_shape(table, 6, SARINS_TT_IO, 1))
        return 0;
    const double *io = sarins_table_row(table, 6);
    if (!(io[1] == 1.0 || io[1] == 2.0 || io[1] == 3.0))
        return 0;
    int64_t a = (int64_t)io[1], m = table[3 * 0 + 1] - 1;
    if (!(m >= 0 && sarins_table_shape(table, 0, m + 1, 1) && sarins_table_shape(table, 1, m + 1, a)
          && sarins_table_shape(table, 2, m + 1, a) && (m == 0 || sarins_table_shape(table, 3, m, a))
          && sarins_table_shape(table, 4, a, 1) && sarins_table_shape(table, 5, a, 1)))
        return 0;
    for (int64_t j = 0; j < a; j++) /* angle_j, rate_j, accel_j */
        if (!(sarins_slots_ok(io + 4 + j, 1, n) && sarins_slots_ok(io + 7 + j, 1, n)
              && sarins_slots_ok(io + 10 + j, 1, n)))
            return 0;
    return sarins_slots_ok(io + 13, 3, n);
}

int sarins_turntable_fmu_step(int64_t *table, int64_t rows, double *buf, int64_t n, double t, double h)
{
    if (table == NULL || buf == NULL || !table_ok(table, rows, n))
        return 1;
    const double *io = sarins_table_row(table, 6);
    if (!(fabs(h - io[0]) <= 1e-9 * io[0]) || io[2] == 0.0)
        return 1;
    double time = t + h;
    if (!isfinite(time))
        return 1;
    int64_t a = (int64_t)io[1];
    double angle[3], rate[3], acc[3];
    sarins_turntable_state(1, &time, table[3 * 0 + 1], a, sarins_table_row(table, 0), sarins_table_row(table, 1),
                           sarins_table_row(table, 2), sarins_table_row(table, 3), sarins_table_row(table, 4),
                           sarins_table_row(table, 5), angle, rate, acc);
    for (int64_t j = 0; j < a; j++) {
        buf[(int64_t)io[4 + j]] = angle[j];
        buf[(int64_t)io[7 + j]] = rate[j];
        buf[(int64_t)io[10 + j]] = acc[j];
    }
    buf[(int64_t)io[13]] = io[3];
    buf[(int64_t)io[14]] = (io[3] - io[3]) / h; /* the constant ambient's rate: 0, NaN if it is not finite */
    buf[(int64_t)io[15]] = time;
    return 0;
}
