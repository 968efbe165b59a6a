/* IMUThermal FMU (native): increment-output IMU with its error and thermal models.
 *
 * The declaration (variables, descriptions, the timing contract) is fmus/imu_thermal_slave.py.  Thin: the
 * slave's parameter checks with logged reasons, the preset and the coefficients that were set (c->set, see
 * model.h) as one flat parameter vector (imu_params.h), then the C core builds the IMU (imu_build.h) at the
 * first step, when the output interval is known, and steps it (sarins_imu_fmu_step, imu.h: the start-of-
 * step motion set, the minor loop, the thermal model, the random streams), the functions the library runs
 * in process.  The static base's Earth rate and gravity come from earth.h.
 *
 * Every array of the IMU lives in one allocation (c->work, sized by the gimbals and the flicker terms the
 * parameters give) and is the work state: FMU state copies it as is.
 *
 * Sub-intervals (n_sub, default 1).  With n_sub = K > 1 the IMU is built for the interval h / K and each step
 * runs K of them (sarins_imu_fmu_step_sub: as if the FMU stepped at h / K, the motion set carried forward
 * with its accelerations); the *_sub arrays (FMI 3.0 outputs, c->a in both versions) hold every
 * sub-interval's increments and gyro_z temperature, the scalar increments their sums.  With K = 1 the step
 * is the one interval of before and the arrays hold its one value.  The sub-interval rows and the scratch
 * of sarins_imu_fmu_step_sub are a second allocation (c->work's sub), not state: rewritten every step.
 * Units: rad, rad/s, rad/s^2, m, m/s, m/s^2, s, degC (the declaration's non-SI display units are the host's).
 */
#include "smath.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dynamics.h"
#include "earth.h"
#include "imu.h"
#include "imu_build.h"
#include "imu_params.h"
#include "model.h"
#include "variables.h"
#include "workers.h"

#define PI 3.14159265358979323846
#define LAT_LIMIT (89.9 * PI / 180.0) /* rad: fmus.slave_support.LAT_LIMIT */
#define SELF_HEATING_LIMIT SARINS_IMU_SELF_HEATING_LIMIT /* degC: the core's bound (imu_build.h) */
#define ABSOLUTE_ZERO (-273.15)       /* degC */
#define AMBIENT_RANGE "ambient temperature must be finite, above absolute zero and at most 500 degC " \
                      "(SARINS_IMU_AMBIENT_MAX)"
#define INT32_LIMIT 2147483647
#define MAX_GIMBALS 3
#define TABLE_ROWS (SARINS_IMU_N_ARRAYS + 3) /* the IMU arrays, the io row, the two held sets */

/* What changes during a run outside the arrays (plain bytes). */
typedef struct {
    double step; /* s: the communication step, fixed by the first fmi2DoStep */
    int started; /* the IMU was built and started at the first step */
} imu_state;

/* The IMU arrays and the FMU's rows, in one block of doubles (the work state), and their table. */
typedef struct {
    int64_t table[3 * TABLE_ROWS]; /* (address, rows, columns) per array (sarins_fmu/core/_lib.py) */
    double par[SARINS_IMU_N_PARAMS]; /* the flat parameters: the preset with the coefficients that were set */
    int n_gimbals, moving, hot;
    double *held, *v_held, *io;    /* the held motion set, the held vehicle set, the io row */
    size_t n_doubles;
    double *block;
    int64_t n_sub;                  /* sub-intervals per step (the parameter n_sub) */
    int given;                      /* sub_inputs = 1: each sub-interval's motion from the *_sub arrays */
    double *sub_dtheta, *sub_dv, *sub_temps, *scratch; /* (n_sub, 3), (n_sub, 3), (n_sub, 6), scratch; n_sub > 1
                                                        * or given */
    double *motion_sub;             /* given: (n_sub, 3 A + 2), the arrays' set of this step (rewritten each step) */
    sarins_workers *pool;           /* threads > 1: the workers of the sub-intervals' minor loops, else NULL */
} imu_work;

static const int MOTION_SLOTS[3][MAX_GIMBALS] = {
    {SARINS_R_angle_1, SARINS_R_angle_2, SARINS_R_angle_3},
    {SARINS_R_rate_1, SARINS_R_rate_2, SARINS_R_rate_3},
    {SARINS_R_accel_1, SARINS_R_accel_2, SARINS_R_accel_3}};
static const int VEHICLE_SLOTS[SARINS_IMU_VEHICLE_SET] = {
    SARINS_R_vehicle_yaw, SARINS_R_vehicle_pitch, SARINS_R_vehicle_roll, SARINS_R_vehicle_yaw_rate,
    SARINS_R_vehicle_pitch_rate, SARINS_R_vehicle_roll_rate, SARINS_R_vehicle_yaw_accel,
    SARINS_R_vehicle_pitch_accel, SARINS_R_vehicle_roll_accel, SARINS_R_base_rate_e, SARINS_R_base_rate_n,
    SARINS_R_base_rate_u, SARINS_R_base_force_e, SARINS_R_base_force_n, SARINS_R_base_force_u};
/* the arrays of the sub-intervals' motion (sub_inputs = 1), in MOTION_SLOTS' order, then the ambient's */
static const int MOTION_ARRAYS[3][MAX_GIMBALS] = {
    {SARINS_A_angle_1_sub, SARINS_A_angle_2_sub, SARINS_A_angle_3_sub},
    {SARINS_A_rate_1_sub, SARINS_A_rate_2_sub, SARINS_A_rate_3_sub},
    {SARINS_A_accel_1_sub, SARINS_A_accel_2_sub, SARINS_A_accel_3_sub}};
static const int OUT_SLOTS[12] = {
    SARINS_R_dtheta_x, SARINS_R_dtheta_y, SARINS_R_dtheta_z, SARINS_R_dv_x, SARINS_R_dv_y, SARINS_R_dv_z,
    SARINS_R_temp_gyro_x, SARINS_R_temp_gyro_y, SARINS_R_temp_gyro_z, SARINS_R_temp_accel_x,
    SARINS_R_temp_accel_y, SARINS_R_temp_accel_z};
/* the arrays of the sub-intervals' increments, in the order of OUT_SLOTS' first six */
static const int SUB_ARRAYS[6] = {SARINS_A_dtheta_x_sub, SARINS_A_dtheta_y_sub, SARINS_A_dtheta_z_sub,
                                  SARINS_A_dv_x_sub, SARINS_A_dv_y_sub, SARINS_A_dv_z_sub};
/* the vehicle's attitude gimbals: mat_nv = Rz(yaw) Rx(pitch) Ry(roll) (sarins_fmu.imu.VEHICLE_ATTITUDE_AXES) */
static const double VEHICLE_AXES[3][3] = {{0.0, 0.0, 1.0}, {1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}};

static int refuse(const sarins_ctx *c, const char *name, double value, const char *what)
{
    sarins_log(c, SARINS_ERROR, "parameter %s = %.17g %s", name, value, what);
    return SARINS_ERROR;
}

/* Value reference of the variable called name (the coefficients are declared under the core's parameter
 * names), or -1. */
static long var_index(const char *name)
{
    for (size_t k = 0; k < SARINS_TABLE.n_vars; k++)
        if (strcmp(SARINS_TABLE.vars[k].name, name) == 0)
            return (long)k;
    return -1;
}

/* The gimbal axes parameter ("z", "x,z", ...: 1 to 3 of x, y, z, outer first) into axes; the count, or 0. */
static int parse_gimbals(const char *text, double axes[MAX_GIMBALS][3])
{
    int n = 0;
    const char *p = text;
    for (;;) {
        while (*p == ' ' || *p == '\t')
            p++;
        if (n == MAX_GIMBALS || (*p != 'x' && *p != 'y' && *p != 'z'))
            return 0;
        for (int i = 0; i < 3; i++)
            axes[n][i] = (i == *p - 'x') ? 1.0 : 0.0;
        n++;
        p++;
        while (*p == ' ' || *p == '\t')
            p++;
        if (*p == '\0')
            return n;
        if (*p != ',')
            return 0;
        p++;
    }
}

/* The preset with every coefficient that was set; SARINS_ERROR with the slave's reasons. */
static int model_params(const sarins_ctx *c, double *par)
{
    const char *preset = c->s[SARINS_S_preset];
    if (sarins_imu_preset_params(preset, par) != 0) {
        char names[128] = "";
        for (int64_t i = 0; i < SARINS_IMU_N_PRESETS; i++)
            snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", i ? ", " : "",
                     sarins_imu_preset_name(i));
        sarins_log(c, SARINS_ERROR, "parameter preset: unknown IMU preset '%s'; choose one of %s", preset, names);
        return SARINS_ERROR;
    }
    int set[SARINS_IMU_N_PARAMS];
    for (int64_t i = 0; i < SARINS_IMU_N_PARAMS; i++) {
        const char *name = sarins_imu_param_name(i);
        long k = var_index(name);
        set[i] = k >= 0 && c->set[k];
        if (!set[i])
            continue;
        double value = c->r[SARINS_TABLE.vars[k].slot];
        if (!isfinite(value))
            return refuse(c, name, value, "is not a finite number");
        if (strncmp(name, "self_heating_", 13) == 0 && !(sm_fabs(value) <= SELF_HEATING_LIMIT)) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %.9g degC is outside [%.9g, %.9g] degC", name, value,
                       -SELF_HEATING_LIMIT, SELF_HEATING_LIMIT);
            return SARINS_ERROR;
        }
        par[i] = value;
    }
    const char *reason = NULL;
    int64_t bad = sarins_imu_check_params(par, &reason);
    if (bad >= 0) {
        sarins_log(c, SARINS_ERROR, "parameter %s = %.17g%s: IMU parameter %s %s", sarins_imu_param_name(bad),
                   par[bad], set[bad] ? "" : " (of the preset, with the coefficients that were set)",
                   sarins_imu_param_name(bad), reason);
        return SARINS_ERROR;
    }
    double bound = 0.0;
    bad = sarins_imu_check_rate_params(par, c->r[SARINS_R_internal_rate], &bound, &reason);
    size_t lower = strlen(SARINS_IMU_LOWER_BOUND);
    if (bad >= 0 && strncmp(reason, SARINS_IMU_LOWER_BOUND, lower) == 0) {
        sarins_log(c, SARINS_ERROR, "parameter %s = %.17g%s is below %.17g at internal_rate %.17g Hz: %s",
                   sarins_imu_param_name(bad), par[bad],
                   set[bad] ? "" : " (of the preset, with the coefficients that were set)", bound,
                   c->r[SARINS_R_internal_rate], reason + lower);
        return SARINS_ERROR;
    }
    if (bad >= 0) { /* the bound derived in the core (imu_build.h sarins_imu_param_bound) */
        sarins_log(c, SARINS_ERROR, "parameter %s = %.17g%s is outside [%.17g, %.17g] at internal_rate %.17g Hz: %s",
                   sarins_imu_param_name(bad), par[bad],
                   set[bad] ? "" : " (of the preset, with the coefficients that were set)", -bound, bound,
                   c->r[SARINS_R_internal_rate], reason);
        return SARINS_ERROR;
    }
    bad = sarins_imu_check_periodic_params(par, c->r[SARINS_R_internal_rate], &reason);
    if (bad >= 0) {
        sarins_log(c, SARINS_ERROR, "parameter %s = %.17g Hz: IMU parameter %s %s (internal_rate %.17g Hz)",
                   sarins_imu_param_name(bad), par[bad], sarins_imu_param_name(bad), reason,
                   c->r[SARINS_R_internal_rate]);
        return SARINS_ERROR;
    }
    return SARINS_OK;
}

/* Every parameter check of the slave at exit_initialization_mode, in its order. */
static int check_parameters(sarins_ctx *c, double axes[MAX_GIMBALS][3], int *n_gimbals)
{
    static const struct { const char *name; int slot; } finite[] = {
        {"lat", SARINS_R_lat}, {"height", SARINS_R_height}, {"base_yaw", SARINS_R_base_yaw},
        {"internal_rate", SARINS_R_internal_rate}, {"aging_days", SARINS_R_aging_days}};
    const double *r = c->r;
    for (size_t k = 0; k < sizeof finite / sizeof finite[0]; k++)
        if (!isfinite(r[finite[k].slot]))
            return refuse(c, finite[k].name, r[finite[k].slot], "is not a finite number");
    if (!(r[SARINS_R_internal_rate] > 0.0))
        return refuse(c, "internal_rate", r[SARINS_R_internal_rate], "must be positive");
    if (!(r[SARINS_R_aging_days] >= 0.0))
        return refuse(c, "aging_days", r[SARINS_R_aging_days], "must not be negative");
    if (!(sm_fabs(r[SARINS_R_lat]) <= LAT_LIMIT)) {
        sarins_log(c, SARINS_ERROR, "parameter lat = %.9g deg is outside [%.9g, %.9g] deg", r[SARINS_R_lat] * 180.0 / PI,
                   -LAT_LIMIT * 180.0 / PI, LAT_LIMIT * 180.0 / PI);
        return SARINS_ERROR;
    }
    if (c->i[SARINS_I_n_sub] < 1 || c->i[SARINS_I_n_sub] > SARINS_TABLE.max_dim) {
        sarins_log(c, SARINS_ERROR, "parameter n_sub = %d must be an integer in [1, %d]", c->i[SARINS_I_n_sub],
                   SARINS_TABLE.max_dim);
        return SARINS_ERROR;
    }
    int given = c->i[SARINS_I_sub_inputs];
    if (sarins_check_sub_switch(c, "sub_inputs", given, "the scalar motion set") != SARINS_OK)
        return SARINS_ERROR;
    if (given == 1 && strcmp(c->s[SARINS_S_base], "static") != 0) {
        sarins_log(c, SARINS_ERROR, "parameter sub_inputs = 1 needs base = static (the vehicle's motion is one set "
                   "per step)");
        return SARINS_ERROR;
    }
    if (c->i[SARINS_I_threads] < 1 || c->i[SARINS_I_threads] > SARINS_WORKERS_MAX) {
        sarins_log(c, SARINS_ERROR, "parameter threads = %d must be an integer in [1, %d]", c->i[SARINS_I_threads],
                   SARINS_WORKERS_MAX);
        return SARINS_ERROR;
    }
    if (c->i[SARINS_I_seed] < 0) {
        sarins_log(c, SARINS_ERROR, "parameter seed = %d must be an integer in [0, %d]", c->i[SARINS_I_seed],
                   INT32_LIMIT);
        return SARINS_ERROR;
    }
    const char *start = c->s[SARINS_S_thermal_start], *base = c->s[SARINS_S_base];
    if (strcmp(start, "hot") != 0 && strcmp(start, "cold") != 0) {
        sarins_log(c, SARINS_ERROR, "thermal_start must be 'hot' or 'cold', got '%s'", start);
        return SARINS_ERROR;
    }
    if (strcmp(base, "static") != 0 && strcmp(base, "input") != 0) {
        sarins_log(c, SARINS_ERROR, "base must be 'static' or 'input', got '%s'", base);
        return SARINS_ERROR;
    }
    *n_gimbals = parse_gimbals(c->s[SARINS_S_gimbals], axes);
    if (*n_gimbals == 0) {
        sarins_log(c, SARINS_ERROR, "gimbals must list 1 to 3 of x, y, z, got '%s'", c->s[SARINS_S_gimbals]);
        return SARINS_ERROR;
    }
    return SARINS_OK;
}

/* The static base's inertial rate and specific force resolved in the base frame t (yawed by yaw in ENU):
 * mat_nt^T (0, W cos L, W sin L) and -mat_nt^T (0, 0, -g), term by term as sarins_fmu.imu.StaticBase. */
static void static_base(double lat, double height, double yaw, double *base)
{
    double c = sm_cos(yaw), s = sm_sin(yaw);
    double mat_tn[3][3] = {{c, s, 0.0}, {-s, c, 0.0}, {0.0, 0.0, 1.0}};
    double w[3] = {0.0, SARINS_EARTH_RATE * sm_cos(lat), SARINS_EARTH_RATE * sm_sin(lat)};
    double g[3] = {0.0, 0.0, -sarins_earth_gravity(lat, height)};
    for (int i = 0; i < 3; i++) {
        base[i] = (mat_tn[i][0] * w[0] + mat_tn[i][1] * w[1]) + mat_tn[i][2] * w[2];
        base[3 + i] = -((mat_tn[i][0] * g[0] + mat_tn[i][1] * g[1]) + mat_tn[i][2] * g[2]);
    }
}

static void imu_free(imu_work *w)
{
    if (w != NULL) {
        sarins_workers_stop(w->pool);
        free(w->sub_dtheta);
        free(w->block);
        free(w);
    }
}

static void imu_release(sarins_ctx *c)
{
    imu_free(c->work);
    c->work = NULL;
}

/* Point table row i at the next rows x cols doubles of the block (NULL while only counting). */
static double *place(imu_work *w, int i, int64_t rows, int64_t cols, size_t *used)
{
    double *at = w->block != NULL ? w->block + *used : NULL;
    w->table[3 * i] = (int64_t)(intptr_t)at;
    w->table[3 * i + 1] = rows;
    w->table[3 * i + 2] = cols;
    *used += (size_t)(rows * cols);
    return at;
}

/* Lay the arrays out in w->block (block NULL: only count them into w->n_doubles). */
static void layout(imu_work *w, int64_t n_axes, int64_t n_flicker)
{
    static const int64_t shapes[SARINS_IMU_N_ARRAYS][2] = {
        {SARINS_IMU_N_CONSTS, 1}, {2, 1}, {4, 6}, {3, 6}, {10, 3}, {7, 3}, {9, 3}, {0, 3}, {2, 3}, {SARINS_IMU_N_STREAMS,
        SARINS_RNG_WORDS}, {8, 6}, {3, 6}, {0, 1}, {0, 6}, {0, 6}, {SARINS_DYN_PAR_ROWS, 6},
        {SARINS_DYN_STATE_ROWS, 6}, {3, 6}};
    size_t used = 0;
    for (int i = 0; i < SARINS_IMU_N_ARRAYS; i++) {
        int flicker = i >= SARINS_IMU_PHI && i <= SARINS_IMU_X_FLICKER; /* the rows of the flicker terms */
        int64_t rows = i == SARINS_IMU_AXES ? n_axes : flicker ? n_flicker : shapes[i][0];
        place(w, i, rows, shapes[i][1], &used);
    }
    w->io = place(w, SARINS_IMU_N_ARRAYS, SARINS_IMU_IO_SIZE, 1, &used);
    w->held = place(w, SARINS_IMU_N_ARRAYS + 1, (w->given ? w->n_sub : 1) * (3 * w->n_gimbals + 2) + 2, 1, &used);
    w->v_held = place(w, SARINS_IMU_N_ARRAYS + 2, SARINS_IMU_VEHICLE_SET + 2, 1, &used);
    w->n_doubles = used;
}

static double *row(const imu_work *w, int i) { return (double *)(intptr_t)w->table[3 * i]; }

/* The io row: the FMU's Real slots for sarins_imu_fmu_step (the expected step is set at the first step). */
static void fill_io(const sarins_ctx *c, imu_work *w)
{
    double *io = w->io;
    io[SARINS_IMU_IO_START] = c->start_time;
    io[SARINS_IMU_IO_GIMBALS] = w->n_gimbals;
    io[SARINS_IMU_IO_MOTION_TIME] = SARINS_R_motion_time;
    io[SARINS_IMU_IO_AMBIENT] = SARINS_R_ambient_temp;
    io[SARINS_IMU_IO_AMBIENT + 1] = SARINS_R_ambient_temp_rate;
    for (int k = 0; k < 3; k++)
        for (int j = 0; j < w->n_gimbals; j++)
            io[SARINS_IMU_IO_MOTION + 3 * k + j] = MOTION_SLOTS[k][j];
    for (int i = 0; i < 12; i++)
        io[SARINS_IMU_IO_OUT + i] = OUT_SLOTS[i];
    io[SARINS_IMU_IO_END_TIME] = SARINS_R_increment_end_time;
    io[SARINS_IMU_IO_VEHICLE] = w->moving;
    io[SARINS_IMU_IO_VEHICLE + 1] = SARINS_R_base_motion_time;
    for (int i = 0; i < SARINS_IMU_VEHICLE_SET; i++)
        io[SARINS_IMU_IO_VEHICLE + 2 + i] = VEHICLE_SLOTS[i];
}

/* The current motion set (angles, rates, accelerations of the A gimbals, ambient and its slope) into out;
 * 0 when a value is not finite. */
static int read_motion(const sarins_ctx *c, int n_gimbals, double *out)
{
    int ok = 1;
    for (int k = 0; k < 3; k++)
        for (int j = 0; j < n_gimbals; j++)
            out[k * n_gimbals + j] = c->r[MOTION_SLOTS[k][j]];
    out[3 * n_gimbals] = c->r[SARINS_R_ambient_temp];
    out[3 * n_gimbals + 1] = c->r[SARINS_R_ambient_temp_rate];
    for (int i = 0; i < 3 * n_gimbals + 2; i++)
        ok = ok && isfinite(out[i]);
    return ok;
}

/* sub_inputs = 1: the motion of the n_sub sub-intervals from the *_sub arrays into out (n_sub rows of
 * read_motion's layout); 0 when a value is not finite. */
static int read_given(const sarins_ctx *c, int n_gimbals, int64_t n_sub, double *out)
{
    int count = 3 * n_gimbals + 2, ok = 1;
    for (int64_t k = 0; k < n_sub; k++) {
        double *row = out + k * count;
        for (int q = 0; q < 3; q++)
            for (int j = 0; j < n_gimbals; j++)
                row[q * n_gimbals + j] = c->a[MOTION_ARRAYS[q][j]][k];
        row[3 * n_gimbals] = c->a[SARINS_A_ambient_temp_sub][k];
        row[3 * n_gimbals + 1] = c->a[SARINS_A_ambient_temp_rate_sub][k];
        for (int i = 0; i < count; i++)
            ok = ok && isfinite(row[i]);
    }
    return ok;
}

static int read_vehicle(const sarins_ctx *c, double *out)
{
    int ok = 1;
    for (int i = 0; i < SARINS_IMU_VEHICLE_SET; i++) {
        out[i] = c->r[VEHICLE_SLOTS[i]];
        ok = ok && isfinite(out[i]);
    }
    return ok;
}

static void keep(double *held, const double *values, int count, double tag)
{
    memcpy(held + 2, values, (size_t)count * sizeof *held);
    held[1] = tag;
    held[0] = 1.0;
}

static int imu_initialize(sarins_ctx *c)
{
    double axes[MAX_GIMBALS][3];
    int n_gimbals = 0;
    int status = check_parameters(c, axes, &n_gimbals);
    if (status != SARINS_OK)
        return status;
    double par[SARINS_IMU_N_PARAMS];
    status = model_params(c, par);
    if (status != SARINS_OK)
        return status;
    double ambient = c->r[SARINS_R_ambient_temp];
    if (!(ambient >= ABSOLUTE_ZERO && ambient <= SARINS_IMU_AMBIENT_MAX)) {
        sarins_log(c, SARINS_ERROR, "ValueError: " AMBIENT_RANGE);
        return SARINS_ERROR;
    }
    double motion[3 * MAX_GIMBALS + 2], vehicle[SARINS_IMU_VEHICLE_SET];
    int moving = strcmp(c->s[SARINS_S_base], "input") == 0;
    if (!read_motion(c, n_gimbals, motion)) {
        sarins_log(c, SARINS_ERROR, "ValueError: motion or ambient inputs contain NaN or infinity");
        return SARINS_ERROR;
    }
    if (moving && !read_vehicle(c, vehicle)) {
        sarins_log(c, SARINS_ERROR, "ValueError: vehicle motion inputs contain NaN or infinity");
        return SARINS_ERROR;
    }
    int64_t n_flicker = sarins_imu_flicker_count(par[SARINS_IMU_P_FLICKER_TAU_MIN], par[SARINS_IMU_P_FLICKER_TAU_MAX]);
    imu_work *w = calloc(1, sizeof *w);
    if (w == NULL) {
        sarins_log(c, SARINS_ERROR, "out of memory for the IMU");
        return SARINS_ERROR;
    }
    memcpy(w->par, par, sizeof par);
    w->n_gimbals = n_gimbals;
    w->moving = moving;
    w->hot = strcmp(c->s[SARINS_S_thermal_start], "hot") == 0;
    w->n_sub = c->i[SARINS_I_n_sub];
    w->given = c->i[SARINS_I_sub_inputs] == 1;
    int64_t n_axes = n_gimbals + (moving ? 3 : 0);
    layout(w, n_axes, n_flicker); /* counts only: the block is not there yet */
    w->block = calloc(w->n_doubles, sizeof(double));
    if (w->block == NULL) {
        sarins_log(c, SARINS_ERROR, "out of memory for the IMU (%llu values)", (unsigned long long)w->n_doubles);
        free(w);
        return SARINS_ERROR;
    }
    layout(w, n_axes, n_flicker);
    int count = 3 * n_gimbals + 2;
    if (w->n_sub > 1 || w->given) { /* the sub-interval rows, the scratch of the step and the arrays' set */
        size_t n_sub_doubles = (size_t)(12 * w->n_sub + SARINS_IMU_SUB_SCRATCH(w->n_sub, n_axes)
                                        + (w->given ? w->n_sub * count : 0));
        w->sub_dtheta = calloc(n_sub_doubles, sizeof(double));
        if (w->sub_dtheta == NULL) {
            sarins_log(c, SARINS_ERROR, "out of memory for n_sub = %d sub-intervals", (int)w->n_sub);
            free(w->block);
            free(w);
            return SARINS_ERROR;
        }
        w->sub_dv = w->sub_dtheta + 3 * w->n_sub;
        w->sub_temps = w->sub_dv + 3 * w->n_sub;
        w->scratch = w->sub_temps + 6 * w->n_sub;
        w->motion_sub = w->given ? w->scratch + SARINS_IMU_SUB_SCRATCH(w->n_sub, n_axes) : NULL;
    }
    if (w->given && !read_given(c, n_gimbals, w->n_sub, w->motion_sub)) {
        sarins_log(c, SARINS_ERROR, "ValueError: the *_sub motion inputs contain NaN or infinity");
        imu_free(w);
        return SARINS_ERROR;
    }
    if (w->given) { /* the ambient of the arrays' set at its start */
        ambient = w->motion_sub[3 * n_gimbals];
        if (!(ambient >= ABSOLUTE_ZERO && ambient <= SARINS_IMU_AMBIENT_MAX)) {
            sarins_log(c, SARINS_ERROR, "ValueError: ambient_temp_sub: " AMBIENT_RANGE);
            imu_free(w);
            return SARINS_ERROR;
        }
    }
    if (c->i[SARINS_I_threads] > 1) {
        int started = 0;
        w->pool = sarins_workers_start(c->i[SARINS_I_threads], &started);
        if (w->pool == NULL) {
            sarins_log(c, SARINS_ERROR, "out of memory for %d threads", c->i[SARINS_I_threads]);
            imu_free(w);
            return SARINS_ERROR;
        }
        if (started < c->i[SARINS_I_threads])
            sarins_log(c, SARINS_WARNING, "threads = %d: %d started (the system refused more, or has no thread "
                       "functions); the same numbers, later", c->i[SARINS_I_threads], started);
    }
    double *ax = row(w, SARINS_IMU_AXES);
    for (int64_t j = 0; j < n_axes; j++)
        memcpy(ax + 3 * j, moving ? (j < 3 ? VEHICLE_AXES[j] : axes[j - 3]) : axes[j], 3 * sizeof *ax);
    if (!moving)
        static_base(c->r[SARINS_R_lat], c->r[SARINS_R_height], c->r[SARINS_R_base_yaw], row(w, SARINS_IMU_BASE));
    fill_io(c, w);
    if (w->given)
        keep(w->held, w->motion_sub, (int)(w->n_sub * count), c->r[SARINS_R_motion_time]);
    else
        keep(w->held, motion, count, c->r[SARINS_R_motion_time]);
    if (moving)
        keep(w->v_held, vehicle, SARINS_IMU_VEHICLE_SET, c->r[SARINS_R_base_motion_time]);
    c->work = w;
    memset(c->state, 0, sizeof(imu_state));
    /* the initial outputs: no increments yet, the temperatures of the thermal start at the ambient */
    static const int heat[6] = {SARINS_IMU_P_SELF_HEATING_GYRO_X, SARINS_IMU_P_SELF_HEATING_GYRO_Y,
                                SARINS_IMU_P_SELF_HEATING_GYRO_Z, SARINS_IMU_P_SELF_HEATING_ACCEL_X,
                                SARINS_IMU_P_SELF_HEATING_ACCEL_Y, SARINS_IMU_P_SELF_HEATING_ACCEL_Z};
    for (int j = 0; j < 6; j++)
        c->r[OUT_SLOTS[6 + j]] = ambient + (w->hot ? par[heat[j]] : 0.0);
    c->r[SARINS_R_increment_end_time] = c->start_time;
    for (int64_t k = 0; k < w->n_sub; k++) /* the increment arrays stay 0 (the glue zeroed them) */
        c->a[SARINS_A_temp_gyro_z_sub][k] = c->r[SARINS_R_temp_gyro_z];
    return SARINS_OK;
}

static int step_error(const sarins_ctx *c, const char *what)
{
    sarins_log(c, SARINS_ERROR, "ValueError: %s", what);
    return SARINS_ERROR;
}

/* The current motion set: the *_sub arrays' (sub_inputs = 1, read into w->motion_sub) or the scalars' (read into
 * motion); NULL with the reason logged when a value is not finite. */
static const double *current_set(const sarins_ctx *c, const imu_work *w, double *motion)
{
    if (w->given ? read_given(c, w->n_gimbals, w->n_sub, w->motion_sub) : read_motion(c, w->n_gimbals, motion))
        return w->given ? w->motion_sub : motion;
    step_error(c, w->given ? "the *_sub motion inputs contain NaN or infinity"
                           : "motion or ambient inputs contain NaN or infinity");
    return NULL;
}

/* The set tagged t among the current one and the held one: *from_held, or 0 with the reason logged. */
static int select_set(const sarins_ctx *c, const double *held, double tag, double t, double h, const char *what,
                      const char *tag_name, int *from_held)
{
    char msg[400];
    if (!isfinite(tag)) {
        snprintf(msg, sizeof msg, "%s is not finite", tag_name);
        return step_error(c, msg);
    }
    if (sm_fabs(tag - t) <= SARINS_IMU_TAG_TOL * h) {
        *from_held = 0;
        return 1;
    }
    if (held[0] != 0.0 && sm_fabs(held[1] - t) <= SARINS_IMU_TAG_TOL * h) {
        *from_held = 1;
        return 1;
    }
    snprintf(msg, sizeof msg, "no %s for the step starting at t=%.9g s: the input %s is %.9g s and the previous "
             "set was tagged %.9g s; the inputs must be the values at t (Jacobi) or at t + h (Gauss-Seidel, upstream "
             "stepped first)", what, t, tag_name, tag, held[1]);
    step_error(c, msg);
    return 0;
}

/* Why sarins_imu_fmu_step refused the step (it changed nothing), in the slave's order and words. */
static int explain(const sarins_ctx *c, const imu_work *w, double t, double h)
{
    const imu_state *st = c->state;
    char msg[400];
    if (sm_fabs(h - st->step) > 1e-9 * st->step) {
        snprintf(msg, sizeof msg, "communication step changed from %.17g s to %.17g s; this FMU needs a fixed step",
                 st->step, h);
        return step_error(c, msg);
    }
    double motion[3 * MAX_GIMBALS + 2], vehicle[SARINS_IMU_VEHICLE_SET];
    const double *current = current_set(c, w, motion);
    if (current == NULL)
        return SARINS_ERROR;
    int from_held = 0;
    double tag = c->r[SARINS_R_motion_time];
    int fixed = tag == SARINS_IMU_NO_TAG && w->held[1] == SARINS_IMU_NO_TAG;
    if (!fixed && !select_set(c, w->held, tag, t, h, "turntable motion", "motion_time", &from_held))
        return SARINS_ERROR;
    const double *consts = row(w, SARINS_IMU_CONSTS), *clock = row(w, SARINS_IMU_CLOCK);
    double now = consts[0] + clock[0] * consts[1] + c->start_time;
    if (sm_fabs(now - t) > SARINS_IMU_TAG_TOL * h) {
        snprintf(msg, sizeof msg, "doStep at t=%.9g s but the IMU stands at %.9g s (steps must follow each other)",
                 t, now);
        return step_error(c, msg);
    }
    if (w->moving) {
        if (!read_vehicle(c, vehicle))
            return step_error(c, "vehicle motion inputs contain NaN or infinity");
        int v_from_held = 0;
        if (!select_set(c, w->v_held, c->r[SARINS_R_base_motion_time], t, h, "vehicle motion", "base_motion_time",
                        &v_from_held))
            return SARINS_ERROR;
    }
    const double *chosen = from_held ? w->held + 2 : current;
    int64_t sets = w->given ? w->n_sub : 1, count = 3 * w->n_gimbals + 2;
    double h_set = h / (double)(w->given ? w->n_sub : 1);
    for (int64_t k = 0; k < sets; k++) {
        const double *set = chosen + k * count;
        double amb_end = set[3 * w->n_gimbals] + set[3 * w->n_gimbals + 1] * h_set;
        if (!(amb_end >= ABSOLUTE_ZERO && amb_end <= SARINS_IMU_AMBIENT_MAX))
            return step_error(c, AMBIENT_RANGE);
    }
    return step_error(c, "the IMU step refused its inputs");
}

/* The first step: the IMU built for the output interval h and started at the ambient of the motion set
 * tagged with the start time (the slave's IMU(...) and reset(ambient0)). */
static int start(sarins_ctx *c, imu_work *w, double t, double h)
{
    double internal_rate = c->r[SARINS_R_internal_rate];
    double interval = w->n_sub > 1 ? h / (double)w->n_sub : h; /* the IMU's output interval */
    double n_sub = interval * internal_rate; /* minor steps per output interval */
    if (sm_fabs(n_sub - sm_nearbyint(n_sub)) > 1e-6 || sm_nearbyint(n_sub) < 1.0) {
        if (w->n_sub > 1)
            sarins_log(c, SARINS_ERROR, "ValueError: output interval %.17g s / n_sub %d = %.17g s is not a whole "
                       "number of minor steps at %.17g Hz", h, (int)w->n_sub, interval, internal_rate);
        else
            sarins_log(c, SARINS_ERROR, "ValueError: output interval %.17g s is not a whole number of minor steps "
                       "at %.17g Hz", h, internal_rate);
        return SARINS_ERROR;
    }
    if (sm_nearbyint(n_sub) > (double)SARINS_IMU_MAX_SUB) {
        sarins_log(c, SARINS_ERROR, "ValueError: output interval %.17g s holds %.17g minor steps at %.17g Hz; "
                   "at most %d", interval, sm_nearbyint(n_sub), internal_rate, SARINS_IMU_MAX_SUB);
        return SARINS_ERROR;
    }
    double motion[3 * MAX_GIMBALS + 2];
    const double *current = current_set(c, w, motion), *chosen = current;
    if (current == NULL)
        return SARINS_ERROR;
    double tag = c->r[SARINS_R_motion_time];
    if (!(tag == SARINS_IMU_NO_TAG && w->held[1] == SARINS_IMU_NO_TAG)) {
        int from_held = 0;
        if (!select_set(c, w->held, tag, t, h, "turntable motion", "motion_time", &from_held))
            return SARINS_ERROR;
        chosen = from_held ? w->held + 2 : current;
    }
    double ambient0 = chosen[3 * w->n_gimbals];
    if (!(ambient0 >= ABSOLUTE_ZERO && ambient0 <= SARINS_IMU_AMBIENT_MAX))
        return step_error(c, AMBIENT_RANGE);
    uint64_t seed = (uint64_t)c->i[SARINS_I_seed];
    if (sarins_imu_build(w->table, TABLE_ROWS, w->par, 0.0, interval, (int64_t)sm_nearbyint(n_sub),
                         c->r[SARINS_R_aging_days] * SARINS_IMU_DAY, seed) != SARINS_IMU_OK
        || sarins_imu_start(w->table, TABLE_ROWS, ambient0, w->hot, seed) != SARINS_IMU_OK)
        return step_error(c, "the IMU could not be built from its parameters");
    w->io[SARINS_IMU_IO_STEP] = h;
    imu_state *st = c->state;
    st->step = h;
    st->started = 1;
    return SARINS_OK;
}

/* Every sub-interval's increments and gyro_z temperature into the *_sub output arrays. */
static void sub_arrays_out(sarins_ctx *c, const imu_work *w)
{
    for (int64_t k = 0; k < w->n_sub; k++) {
        for (int i = 0; i < 3; i++) {
            c->a[SUB_ARRAYS[i]][k] = w->sub_dtheta[3 * k + i];
            c->a[SUB_ARRAYS[3 + i]][k] = w->sub_dv[3 * k + i];
        }
        c->a[SARINS_A_temp_gyro_z_sub][k] = w->sub_temps[6 * k + 2];
    }
}

static int imu_do_step(sarins_ctx *c, double t, double h)
{
    imu_work *w = c->work;
    imu_state *st = c->state;
    if (!st->started) {
        int status = start(c, w, t, h);
        if (status != SARINS_OK)
            return status;
    }
    if (w->given) {
        if (!read_given(c, w->n_gimbals, w->n_sub, w->motion_sub)
            || sarins_imu_fmu_step_given(w->table, TABLE_ROWS, c->r, (int64_t)SARINS_TABLE.n_real, t, h, w->n_sub,
                                         w->motion_sub, w->sub_dtheta, w->sub_dv, w->sub_temps, w->scratch,
                                         w->pool) != 0)
            return explain(c, w, t, h);
        sub_arrays_out(c, w);
        return SARINS_OK;
    }
    if (w->n_sub == 1) {
        if (sarins_imu_fmu_step(w->table, TABLE_ROWS, c->r, (int64_t)SARINS_TABLE.n_real, t, h) != 0)
            return explain(c, w, t, h);
        for (int i = 0; i < 6; i++)
            c->a[SUB_ARRAYS[i]][0] = c->r[OUT_SLOTS[i]];
        c->a[SARINS_A_temp_gyro_z_sub][0] = c->r[SARINS_R_temp_gyro_z];
        return SARINS_OK;
    }
    if (sarins_imu_fmu_step_sub(w->table, TABLE_ROWS, c->r, (int64_t)SARINS_TABLE.n_real, t, h, w->n_sub,
                                w->sub_dtheta, w->sub_dv, w->sub_temps, w->scratch) != 0)
        return explain(c, w, t, h);
    sub_arrays_out(c, w);
    return SARINS_OK;
}

static size_t imu_work_state_size(const sarins_ctx *c)
{
    const imu_work *w = c->work;
    return w->n_doubles * sizeof(double);
}

static void imu_save_work_state(const sarins_ctx *c, unsigned char *dst)
{
    const imu_work *w = c->work;
    memcpy(dst, w->block, w->n_doubles * sizeof(double));
}

static int imu_load_work_state(sarins_ctx *c, const unsigned char *src, size_t n)
{
    imu_work *w = c->work;
    if (n != w->n_doubles * sizeof(double)) {
        sarins_log(c, SARINS_ERROR, "the IMU state has %llu bytes, this instance's parameters give %llu",
                   (unsigned long long)n, (unsigned long long)(w->n_doubles * sizeof(double)));
        return SARINS_ERROR;
    }
    memcpy(w->block, src, n);
    return SARINS_OK;
}

/* Every field of the state within what do_step relies on (model.h, State validation); the IMU arrays (the
 * work state) are checked for their size by imu_load_work_state. */
static int imu_check_state(const sarins_ctx *c, int running)
{
    const imu_state *s = c->state;
    if (!sarins_state_int(c, "started", s->started, 0, running ? 1 : 0)
        || !sarins_state_real(c, "step", s->step, s->started ? 1e-300 : 0.0, s->started ? 1e300 : 0.0))
        return SARINS_ERROR;
    return SARINS_OK;
}

const sarins_model sarins_model_desc = {
    .table = &SARINS_TABLE,
    .state_size = sizeof(imu_state),
    .state_version = 2, /* 2: the periodic row (imu.h SARINS_IMU_PERIODIC) in the work state */
    .check_state = imu_check_state,
    .initialize = imu_initialize,
    .do_step = imu_do_step,
    .release = imu_release,
    .work_state_size = imu_work_state_size,
    .save_work_state = imu_save_work_state,
    .load_work_state = imu_load_work_state,
};
