#if defined(_MSC_VER) && !defined(_CRT_SECURE_NO_WARNINGS)
#define _CRT_SECURE_NO_WARNINGS /* fopen and fread are the portable C11 calls; MSVC's /W4 would flag them */
#endif
#include "smath.h"

#include "rls.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "matrix.h"
#include "netfile.h"
#include "report.h"

double sarins_drift_model_value(const double *coef, double t) { return (coef[0] * t + coef[1]) * t + coef[2]; }

double sarins_rls_factor(double forgetting_factor, double dt, double time_scale)
{
    if (time_scale == 0.0)
        return forgetting_factor;
    return sm_pow(forgetting_factor, dt / time_scale);
}

void sarins_rls_gain_step(double *x, double *p, const double *h, double z, double lam)
{
    double ph[3], k[3];
    /* P h */
    sarins_matvec(3, p, h, ph);
    /* K = P h / (lam + h' P h) */
    double hph = 0.0;
    for (int i = 0; i < 3; i++)
        hph += h[i] * ph[i];
    double denom = lam + hph;
    for (int i = 0; i < 3; i++)
        k[i] = ph[i] / denom;
    /* x = x + K (z - h' x) */
    double hx = 0.0;
    for (int i = 0; i < 3; i++)
        hx += h[i] * x[i];
    double innovation = z - hx;
    for (int i = 0; i < 3; i++)
        x[i] = x[i] + k[i] * innovation;
    /* P = (P - K (P h)') / lam, symmetrized */
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            p[3 * i + j] = (p[3 * i + j] - k[i] * ph[j]) / lam;
    sarins_symmetrize(3, p);
}

int sarins_rls_check_covariance(const double *p, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    double l[9];
    for (int i = 0; i < 9; i++)
        if (!isfinite(p[i]))
            return sarins_fail(&r, SARINS_RLS_BAD, "covariance holds NaN or infinity");
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (!(sm_fabs(p[3 * i + j] - p[3 * j + i]) <= 1e-9 * sm_fabs(p[3 * j + i])))
                return sarins_fail(&r, SARINS_RLS_BAD, "covariance is not symmetric");
    if (sarins_cholesky(3, p, l) != 0)
        return sarins_fail(&r, SARINS_RLS_BAD, "covariance is not positive definite");
    return SARINS_RLS_OK;
}

int sarins_rls_check_settings(double forgetting_factor, double time_scale, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    char text[40];
    if (!(isfinite(forgetting_factor) && forgetting_factor > 0.0 && forgetting_factor <= 1.0)) {
        sarins_format_number(text, sizeof text, forgetting_factor);
        return sarins_fail(&r, SARINS_RLS_BAD, "forgetting_factor must be in (0, 1], got %s", text);
    }
    if (!(isfinite(time_scale) && time_scale >= 0.0)) {
        sarins_format_number(text, sizeof text, time_scale);
        return sarins_fail(&r, SARINS_RLS_BAD, "time_scale must be positive (s) or per update, got %s", text);
    }
    return SARINS_RLS_OK;
}

int sarins_rls_init(sarins_rls *s, const double *x, const double *p, double time, double forgetting_factor,
                    double time_scale, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    for (int i = 0; i < 3; i++)
        if (!isfinite(x[i]))
            return sarins_fail(&r, SARINS_RLS_BAD, "parameters holds NaN or infinity");
    if (!isfinite(time))
        return sarins_fail(&r, SARINS_RLS_BAD, "time must be finite");
    if (sarins_rls_check_settings(forgetting_factor, time_scale, msg, size) != SARINS_RLS_OK
        || sarins_rls_check_covariance(p, msg, size) != SARINS_RLS_OK)
        return SARINS_RLS_BAD;
    for (int i = 0; i < 3; i++)
        s->x[i] = x[i];
    for (int i = 0; i < 9; i++)
        s->p[i] = p[i];
    sarins_symmetrize(3, s->p);
    s->time = time;
    s->forgetting_factor = forgetting_factor;
    s->time_scale = time_scale;
    s->n_updates = 0;
    return SARINS_RLS_OK;
}

int sarins_rls_update(sarins_rls *s, double temperature, double drift, double time, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    if (!(isfinite(temperature) && isfinite(drift) && isfinite(time)))
        return sarins_fail(&r, SARINS_RLS_BAD, "temperature, drift and time must be finite");
    if (time < s->time) {
        char a[40], b[40];
        sarins_format_number(a, sizeof a, time);
        sarins_format_number(b, sizeof b, s->time);
        return sarins_fail(&r, SARINS_RLS_BAD, "update at %s s is earlier than the state time %s s", a, b);
    }
    double lam = sarins_rls_factor(s->forgetting_factor, time - s->time, s->time_scale);
    const double h[3] = {temperature * temperature, temperature, 1.0};
    double x[3], p[9];
    for (int i = 0; i < 3; i++)
        x[i] = s->x[i];
    for (int i = 0; i < 9; i++)
        p[i] = s->p[i];
    sarins_rls_gain_step(x, p, h, drift, lam);
    for (int i = 0; i < 9; i++)
        if (!isfinite(p[i]) || (i < 3 && !isfinite(x[i])) || (i % 4 == 0 && !(p[i] > 0.0)))
            return sarins_fail(&r, SARINS_RLS_BAD, "the update at %.9g degC overflows or loses the model's "
                                                   "information (P not finite or not positive)", temperature);
    for (int i = 0; i < 3; i++)
        s->x[i] = x[i];
    for (int i = 0; i < 9; i++)
        s->p[i] = p[i];
    s->time = time;
    s->n_updates += 1;
    return SARINS_RLS_OK;
}

int sarins_rls_prior_covariance(double points, double t_min, double t_max, double *p0, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    if (!(isfinite(points) && points > 0.0 && isfinite(t_min) && isfinite(t_max) && t_max > t_min))
        return sarins_fail(&r, SARINS_RLS_BAD, "prior points must be positive and t_max > t_min");
    enum { N = SARINS_RLS_PRIOR_NODES };
    double h[N][3], info[9], inv[9];
    double step = (t_max - t_min) / (double)(N - 1);
    for (int i = 0; i < N; i++) {
        double t = (i == N - 1) ? t_max : (double)i * step + t_min;
        h[i][0] = t * t;
        h[i][1] = t;
        h[i][2] = 1.0;
    }
    /* information = (H' H) points / 11 */
    double w = points / (double)N;
    for (int j = 0; j < 3; j++)
        for (int k = 0; k < 3; k++) {
            double sum = 0.0;
            for (int i = 0; i < N; i++)
                sum += h[i][j] * h[i][k];
            info[3 * j + k] = sum * w;
        }
    if (sarins_spd_inverse(3, info, inv) != 0)
        return sarins_fail(&r, SARINS_RLS_BAD, "the prior's information matrix is singular (t_min .. t_max too "
                                               "narrow or points too small or large)");
    sarins_symmetrize(3, inv);
    for (int i = 0; i < 9; i++)
        p0[i] = inv[i];
    return SARINS_RLS_OK;
}

int sarins_rls_check(const sarins_rls *s, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    for (int i = 0; i < 3; i++)
        if (!isfinite(s->x[i]))
            return sarins_fail(&r, SARINS_RLS_BAD, "RLS parameters not finite");
    for (int i = 0; i < 9; i++)
        if (!isfinite(s->p[i]))
            return sarins_fail(&r, SARINS_RLS_BAD, "RLS covariance not finite");
    for (int i = 0; i < 3; i++) {
        if (!(s->p[4 * i] > 0.0))
            return sarins_fail(&r, SARINS_RLS_BAD, "RLS covariance diagonal not positive");
        for (int j = 0; j < i; j++)
            if (s->p[3 * i + j] != s->p[3 * j + i])
                return sarins_fail(&r, SARINS_RLS_BAD, "RLS covariance not symmetric");
    }
    if (!isfinite(s->time))
        return sarins_fail(&r, SARINS_RLS_BAD, "RLS time not finite");
    if (s->n_updates < 0 || s->n_updates > ((int64_t)1 << 53))
        return sarins_fail(&r, SARINS_RLS_BAD, "RLS update count not 0 .. 2^53");
    return sarins_rls_check_settings(s->forgetting_factor, s->time_scale, msg, size);
}

/* The array name of shape (d0, d1) (ndim 0: a scalar), or NULL with the reason. */
static const sarins_netfile_array *array(const sarins_netfile *f, const char *name, uint32_t ndim, uint64_t d0,
                                         uint64_t d1, report *r)
{
    const sarins_netfile_array *a = sarins_netfile_find(f, name);
    if (a == NULL) {
        sarins_fail(r, SARINS_RLS_BAD, "missing array '%s'", name);
        return NULL;
    }
    if (a->ndim != ndim || a->dim[0] != d0 || a->dim[1] != d1) {
        sarins_fail(r, SARINS_RLS_BAD, "array '%s' must have shape (%s), got ndim %u (%llu, %llu)", name,
                    ndim == 0 ? "" : ndim == 1 ? "3," : "3, 3", (unsigned)a->ndim, (unsigned long long)a->dim[0],
                    (unsigned long long)a->dim[1]);
        return NULL;
    }
    for (uint64_t i = 0; i < a->count; i++)
        if (!isfinite(sarins_netfile_value(f, a, i))) {
            sarins_fail(r, SARINS_RLS_BAD, "array '%s' holds NaN or infinity", name);
            return NULL;
        }
    return a;
}

int sarins_rls_from_model(const unsigned char *buf, size_t n, sarins_rls *s, char *msg, size_t size)
{
    static const char *const NAMES[6] = {"parameters", "covariance", "time", "n_updates", "forgetting_factor",
                                         "time_scale"};
    report r = sarins_report(msg, size);
    sarins_netfile f;
    if (n > SARINS_RLS_FILE_MAX)
        return sarins_fail(&r, SARINS_RLS_BAD, "%llu bytes: larger than the %d bytes an RLS model file may have",
                           (unsigned long long)n, SARINS_RLS_FILE_MAX);
    if (sarins_netfile_parse(buf, n, &f, msg, size) != SARINS_NETFILE_OK)
        return SARINS_RLS_BAD;
    if (f.kind != SARINS_NET_KIND_RLS)
        return sarins_fail(&r, SARINS_RLS_BAD, "model kind %u, an RLS model file has kind %d", (unsigned)f.kind,
                           SARINS_NET_KIND_RLS);
    for (uint32_t k = 0; k < f.n_arrays; k++) {
        int known = 0;
        for (int j = 0; j < 6; j++)
            known |= strcmp(f.arrays[k].name, NAMES[j]) == 0;
        if (!known)
            return sarins_fail(&r, SARINS_RLS_BAD, "unexpected array '%s'", f.arrays[k].name);
    }
    const sarins_netfile_array *a[6];
    for (int j = 0; j < 6; j++) {
        a[j] = array(&f, NAMES[j], j == 0 ? 1 : j == 1 ? 2 : 0, 3 - 2 * (j > 1), j == 1 ? 3 : 1, &r);
        if (a[j] == NULL)
            return SARINS_RLS_BAD;
    }
    double x[3], p[9];
    for (int i = 0; i < 3; i++)
        x[i] = sarins_netfile_value(&f, a[0], (uint64_t)i);
    for (int i = 0; i < 9; i++)
        p[i] = sarins_netfile_value(&f, a[1], (uint64_t)i);
    double count = sarins_netfile_value(&f, a[3], 0), time_scale = sarins_netfile_value(&f, a[5], 0);
    if (!(count >= 0.0 && count <= 9007199254740992.0 && count == (double)(int64_t)count))
        return sarins_fail(&r, SARINS_RLS_BAD, "'n_updates' must be a whole number 0 .. 2^53, got %.17g", count);
    if (time_scale < 0.0)
        return sarins_fail(&r, SARINS_RLS_BAD, "'time_scale' must be positive (s) or 0 (per update), got %.17g",
                           time_scale);
    sarins_rls state;
    if (sarins_rls_init(&state, x, p, sarins_netfile_value(&f, a[2], 0), sarins_netfile_value(&f, a[4], 0),
                        time_scale, msg, size) != SARINS_RLS_OK)
        return SARINS_RLS_BAD;
    state.n_updates = (int64_t)count;
    *s = state;
    return SARINS_RLS_OK;
}

int sarins_rls_load_file(const char *path, sarins_rls *s, char *msg, size_t size)
{
    report r = sarins_report(msg, size);
    unsigned char buf[SARINS_RLS_FILE_MAX + 1]; /* one byte more: a longer file is seen as such */
    if (path == NULL || path[0] == '\0')
        return sarins_fail(&r, SARINS_RLS_BAD, "no file named");
    FILE *fp = fopen(path, "rb");
    if (fp == NULL)
        return sarins_fail(&r, SARINS_RLS_BAD, "no such file or it cannot be opened");
    size_t n = 0, k;
    while (n < sizeof buf && (k = fread(buf + n, 1, sizeof buf - n, fp)) > 0)
        n += k;
    int failed = ferror(fp);
    fclose(fp);
    if (failed)
        return sarins_fail(&r, SARINS_RLS_BAD, "cannot be read (a directory, or a read error)");
    return sarins_rls_from_model(buf, n, s, msg, size);
}

int64_t sarins_rls_layout(int64_t *offsets)
{
    offsets[0] = (int64_t)offsetof(sarins_rls, x);
    offsets[1] = (int64_t)offsetof(sarins_rls, p);
    offsets[2] = (int64_t)offsetof(sarins_rls, time);
    offsets[3] = (int64_t)offsetof(sarins_rls, forgetting_factor);
    offsets[4] = (int64_t)offsetof(sarins_rls, time_scale);
    offsets[5] = (int64_t)offsetof(sarins_rls, n_updates);
    return (int64_t)sizeof(sarins_rls);
}
