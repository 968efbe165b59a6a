#include "smath.h"

#include "turntable.h"

/* Number of breakpoints <= t, less one: the segment holding t (-1 before the start). */
static int64_t segment(const double *times, int64_t n_times, double t)
{
    int64_t lo = 0, hi = n_times; /* first index with times[i] > t lies in [lo, hi] */
    while (lo < hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (times[mid] <= t)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo - 1;
}

void sarins_turntable_state(int64_t n, const double *t, int64_t n_times, int64_t n_axes, const double *times,
                            const double *angle_bp, const double *rate_bp, const double *accel,
                            const double *angle0, const double *rate0, double *angle, double *rate, double *acc)
{
    int64_t last = n_times - 1;
    for (int64_t k = 0; k < n; k++) {
        int64_t s = segment(times, n_times, t[k]);
        double *ang = angle + n_axes * k, *rat = rate + n_axes * k, *ac = acc + n_axes * k;
        if (s < 0) { /* before the schedule: hold the initial rate */
            for (int64_t j = 0; j < n_axes; j++) {
                ac[j] = 0.0;
                rat[j] = rate0[j];
                /* angle = angle0 + rate0 (t - t0) */
                ang[j] = angle0[j] + rate0[j] * (t[k] - times[0]);
            }
            continue;
        }
        double tau = t[k] - times[s];
        for (int64_t j = 0; j < n_axes; j++) {
            double a = (s < last) ? accel[n_axes * s + j] : 0.0;
            ac[j] = a;
            /* rate = rate_bp + a tau ; angle = angle_bp + rate_bp tau + a tau^2 / 2 */
            rat[j] = rate_bp[n_axes * s + j] + a * tau;
            ang[j] = angle_bp[n_axes * s + j] + rate_bp[n_axes * s + j] * tau + 0.5 * a * tau * tau;
        }
    }
}
