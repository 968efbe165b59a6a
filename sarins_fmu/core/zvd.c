#include "smath.h"
#include "report.h"
#include "zvd.h"


int sarins_zvd_init(sarins_zvd *s, const double *config, char *msg, size_t size)
{
    for (int i = 0; i < SARINS_ZVD_CONFIG; i++)
        if (!isfinite(config[i])) {
            sarins_say(msg, size, "a zero-velocity detector setting is not finite");
            return 1;
        }
    double n = config[SARINS_ZVD_WINDOW];
    if (n < 2.0 || n > (double)SARINS_ZVD_MAX_WINDOW || n != sm_nearbyint(n)) {
        sarins_say(msg, size, "the zero-velocity detector window must be a whole number of samples, 2 .. "
                              SARINS_ZVD_STR(SARINS_ZVD_MAX_WINDOW));
        return 1;
    }
    if (!(config[SARINS_ZVD_STEP] > 0.0 && config[SARINS_ZVD_VRW] > 0.0 && config[SARINS_ZVD_ARW] > 0.0 &&
          config[SARINS_ZVD_GAMMA] > 0.0)) {
        sarins_say(msg, size, "the zero-velocity detector step, noise densities and threshold must be positive");
        return 1;
    }
    double h = config[SARINS_ZVD_STEP], vrw = config[SARINS_ZVD_VRW], arw = config[SARINS_ZVD_ARW];
    s->window = (int64_t)n;
    s->step = h;
    s->gamma = config[SARINS_ZVD_GAMMA];
    /* sigma^2 = density^2 / h */
    s->inv_var_f = h / (vrw * vrw);
    s->inv_var_w = h / (arw * arw);
    s->count = 0;
    for (int64_t j = 0; j < SARINS_ZVD_MAX_WINDOW; j++)
        for (int i = 0; i < 3; i++)
            s->f[j][i] = s->w[j][i] = 0.0;
    return 0;
}

/* sum_j |x_j - xbar|^2 over the first n rows of x (two passes) */
static double spread(const double (*x)[3], int64_t n)
{
    double mean[3] = {0.0, 0.0, 0.0}, sum = 0.0;
    for (int64_t j = 0; j < n; j++)
        for (int i = 0; i < 3; i++)
            mean[i] += x[j][i];
    for (int i = 0; i < 3; i++)
        mean[i] /= (double)n;
    for (int64_t j = 0; j < n; j++)
        for (int i = 0; i < 3; i++) {
            double d = x[j][i] - mean[i];
            sum += d * d;
        }
    return sum;
}

int sarins_zvd_push(sarins_zvd *s, const double *dtheta, const double *dv, double *stat)
{
    for (int i = 0; i < 3; i++)
        if (!isfinite(dtheta[i]) || !isfinite(dv[i]))
            return -1;
    int64_t slot = s->count % s->window;
    for (int i = 0; i < 3; i++) {
        s->f[slot][i] = dv[i] / s->step;
        s->w[slot][i] = dtheta[i] / s->step;
    }
    s->count++;
    if (s->count < s->window) {
        *stat = -1.0;
        return 0;
    }
    /* T = sum |f - fbar|^2 / sigma_f^2 + sum |w - wbar|^2 / sigma_w^2 (the order of the ring does not matter) */
    double t = spread((const double (*)[3])s->f, s->window) * s->inv_var_f +
               spread((const double (*)[3])s->w, s->window) * s->inv_var_w;
    *stat = t;
    return t <= s->gamma ? 1 : 0;
}

int sarins_zvd_run(sarins_zvd *s, int64_t n, const double *dtheta, const double *dv, double *stat, double *flag)
{
    for (int64_t k = 0; k < n; k++) {
        int r = sarins_zvd_push(s, dtheta + 3 * k, dv + 3 * k, stat + k);
        if (r < 0)
            return 1;
        flag[k] = (double)r;
    }
    return 0;
}

int64_t sarins_zvd_size(void) { return (int64_t)sizeof(sarins_zvd); }

int sarins_zvd_check(const sarins_zvd *s, char *msg, size_t size)
{
    if (!(s->window >= 2 && s->window <= SARINS_ZVD_MAX_WINDOW && s->count >= 0)) {
        sarins_say(msg, size, "zero-velocity detector: the window or the sample count is out of range");
        return 1;
    }
    const double v[4] = {s->step, s->inv_var_f, s->inv_var_w, s->gamma};
    for (int i = 0; i < 4; i++)
        if (!(isfinite(v[i]) && v[i] > 0.0)) {
            sarins_say(msg, size, "zero-velocity detector: the step, inverse variances and threshold must be positive");
            return 1;
        }
    for (int64_t j = 0; j < s->window; j++)
        for (int i = 0; i < 3; i++)
            if (!isfinite(s->f[j][i]) || !isfinite(s->w[j][i])) {
                sarins_say(msg, size, "zero-velocity detector: a sample of the window is not finite");
                return 1;
            }
    return 0;
}
