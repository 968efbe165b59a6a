#include "rls.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#include "matrix.h"
#include "modelfile.h"
#include "report.h"

double sarins_drift_model_value(const double *coef, double t) { return (coef[0] * t + coef[1]) * t + coef[2]; }

double sarins_rls_factor(double forgetting_factor, double dt, double time_scale)
{
    if (time_scale == 0.0)
        return forgetting_factor;
    return pow(forgetting_factor, dt / time_scale);
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
            if (!(fabs(p[3 * i + j] - p[3 * j + i]) <= 1e-9 * fabs(p[3 * j + i])))
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
    sarins_rls_gain_step(s->x, s->p, h, drift, lam);
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
    if (s->n_updates < 0)
        return sarins_fail(&r, SARINS_RLS_BAD, "RLS update count negative");
    return sarins_rls_check_settings(s->forgetting_factor, s->time_scale, msg, size);
}

/* The entry name with this dtype and shape (ndim 0: a scalar), or NULL with the reason. */
static const sarins_mf_entry *entry(const sarins_mf *mf, const char *name, uint32_t dtype, uint32_t ndim,
                                    uint32_t d0, uint32_t d1, report *r)
{
    static const char *const TYPES[3] = {"null", "float64", "int64"};
    const sarins_mf_entry *e = sarins_mf_find(mf, name);
    if (e == NULL) {
        sarins_fail(r, SARINS_RLS_BAD, "missing entry '%s'", name);
        return NULL;
    }
    if (e->dtype != dtype || e->ndim != ndim || e->dims[0] != d0 || e->dims[1] != d1) {
        sarins_fail(r, SARINS_RLS_BAD, "entry '%s' must be %s of shape (%s%s%s), got %s of rank %lu", name,
                    TYPES[dtype], ndim > 0 ? "3" : "", ndim > 1 ? ", 3" : "", ndim == 1 ? "," : "",
                    TYPES[e->dtype], (unsigned long)e->ndim);
        return NULL;
    }
    return e;
}

int sarins_rls_from_model(const unsigned char *buf, size_t n, sarins_rls *s, char *msg, size_t size)
{
    static const char *const NAMES[6] = {"parameters", "covariance", "time", "n_updates",
                                         "settings.forgetting_factor", "settings.time_scale"};
    report r = sarins_report(msg, size);
    sarins_mf mf;
    if (n > SARINS_RLS_FILE_MAX)
        return sarins_fail(&r, SARINS_RLS_BAD, "larger than the %d bytes an RLS model file may have",
                           SARINS_RLS_FILE_MAX);
    if (sarins_mf_parse(buf, n, SARINS_RLS_KIND, &mf, msg, size) != SARINS_MF_OK)
        return SARINS_RLS_BAD;
    if (mf.kind_version != SARINS_RLS_KIND_VERSION)
        return sarins_fail(&r, SARINS_RLS_BAD, "format version %lu not supported (readable: [%d])",
                           (unsigned long)mf.kind_version, SARINS_RLS_KIND_VERSION);
    for (uint32_t k = 0; k < mf.n_entries; k++) {
        int known = 0;
        for (int j = 0; j < 6; j++)
            known |= strcmp(mf.entries[k].name, NAMES[j]) == 0;
        if (!known)
            return sarins_fail(&r, SARINS_RLS_BAD, "unexpected entry '%s'", mf.entries[k].name);
    }
    const sarins_mf_entry *x = entry(&mf, "parameters", SARINS_MF_F64, 1, 3, 0, &r);
    const sarins_mf_entry *p = x ? entry(&mf, "covariance", SARINS_MF_F64, 2, 3, 3, &r) : NULL;
    const sarins_mf_entry *t = p ? entry(&mf, "time", SARINS_MF_F64, 0, 0, 0, &r) : NULL;
    const sarins_mf_entry *u = t ? entry(&mf, "n_updates", SARINS_MF_I64, 0, 0, 0, &r) : NULL;
    const sarins_mf_entry *lam = u ? entry(&mf, "settings.forgetting_factor", SARINS_MF_F64, 0, 0, 0, &r) : NULL;
    const sarins_mf_entry *m = lam ? sarins_mf_find(&mf, "settings.time_scale") : NULL;
    if (lam == NULL)
        return SARINS_RLS_BAD;
    if (m == NULL)
        return sarins_fail(&r, SARINS_RLS_BAD, "missing entry 'settings.time_scale'");
    if (!(m->dtype == SARINS_MF_NULL || (m->dtype == SARINS_MF_F64 && m->ndim == 0)))
        return sarins_fail(&r, SARINS_RLS_BAD, "entry 'settings.time_scale' must be a float64 scalar or null");
    double xv[3], pv[9];
    for (int i = 0; i < 3; i++)
        xv[i] = sarins_mf_f64(buf, x, (uint64_t)i);
    for (int i = 0; i < 9; i++)
        pv[i] = sarins_mf_f64(buf, p, (uint64_t)i);
    double time_scale = 0.0;
    if (m->dtype == SARINS_MF_F64) {
        time_scale = sarins_mf_f64(buf, m, 0);
        if (!(time_scale > 0.0))
            return sarins_fail(&r, SARINS_RLS_BAD, "settings.time_scale must be positive (s) or null");
    }
    int64_t n_updates = sarins_mf_i64(buf, u, 0);
    if (n_updates < 0)
        return sarins_fail(&r, SARINS_RLS_BAD, "'n_updates' must be an integer >= 0, got %lld", (long long)n_updates);
    sarins_rls state;
    if (sarins_rls_init(&state, xv, pv, sarins_mf_f64(buf, t, 0), sarins_mf_f64(buf, lam, 0), time_scale, msg, size)
        != SARINS_RLS_OK)
        return SARINS_RLS_BAD;
    state.n_updates = n_updates;
    *s = state;
    return SARINS_RLS_OK;
}

int sarins_rls_load_file(const char *path, sarins_rls *s, char *msg, size_t size)
{
    unsigned char buf[SARINS_RLS_FILE_MAX];
    size_t n;
    if (sarins_mf_read_file(path, buf, sizeof buf, &n, msg, size) != SARINS_MF_OK)
        return SARINS_RLS_BAD;
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
