/* RBFIdentifier FMU (native): seed 000's axial-drift identification from the INS latitude error.
 *
 * The declaration (variables, the time-tag contract) is fmus/rbf_identifier_slave.py.  The model is read at
 * initialisation from a binary model file (sarins_fmu/core/netfile.h): model_file when given, else
 * resources/axial_rbf_<model_kind>.bin (the shipped hot and cold models), and evaluated by the C core's
 * sarins_axial_drift (netmodel.h), the function the library's DriftIdentifier calls in process.  Units:
 * lat_error rad, temperatures degC, times s, axial_drift rad/s (the network answers deg/h).
 *
 * Held between steps (the FMU state): the outputs (axial_drift, apply_from, identified) in the value arrays
 * and the communication step in the state struct; the model in c->work depends on the parameters only.
 */
#include "smath.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"
#include "netfile.h"
#include "netmodel.h"
#include "variables.h"

#define DPH_TO_RPS ((3.141592653589793 / 180.0) / 3600.0) /* rad/s per deg/h, as sarins_fmu.units */
#define STEP_TOL 1e-9 /* relative: a communication step equal to the first one */
#define TAG_TOL 1e-6  /* of a step: two time tags closer than this name the same communication point */
#define PATH_MAX_BYTES 4096

typedef struct {
    double step; /* s, fixed by the first doStep */
    int have_step;
} ri_state;

/* path into out with surrounding white space removed (the slave's str.strip()) */
static void strip(const char *s, char *out, size_t n)
{
    while (*s != '\0' && isspace((unsigned char)*s))
        s++;
    size_t len = strlen(s);
    while (len > 0 && isspace((unsigned char)s[len - 1]))
        len--;
    if (len >= n)
        len = n - 1;
    memcpy(out, s, len);
    out[len] = '\0';
}

static int check_parameters(sarins_ctx *c)
{
    static const struct { const char *name; int slot; } params[] = {
        {"trigger_time", SARINS_R_trigger_time}, {"latency", SARINS_R_latency}};
    for (int k = 0; k < 2; k++)
        if (!isfinite(c->r[params[k].slot])) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %g is not a finite number", params[k].name,
                       c->r[params[k].slot]);
            return SARINS_ERROR;
        }
    for (int k = 0; k < 2; k++)
        if (!(c->r[params[k].slot] >= 0.0)) {
            sarins_log(c, SARINS_ERROR, "parameter %s = %.17g must not be negative", params[k].name,
                       c->r[params[k].slot]);
            return SARINS_ERROR;
        }
    return SARINS_OK;
}

/* The model file's path: model_file, else the shipped model of model_kind in resources; *param and *value
 * name the parameter that chose it (for the messages). */
static int model_path(sarins_ctx *c, char *path, size_t n, const char **param, const char **value)
{
    char file[SARINS_STRING_MAX];
    strip(c->s[SARINS_S_model_file], file, sizeof file);
    if (file[0] != '\0') {
        *param = "model_file";
        *value = c->s[SARINS_S_model_file];
        snprintf(path, n, "%s", file);
        return SARINS_OK;
    }
    *param = "model_kind";
    *value = c->s[SARINS_S_model_kind];
    const char *kind = c->s[SARINS_S_model_kind];
    if (strcmp(kind, "hot") != 0 && strcmp(kind, "cold") != 0) {
        sarins_log(c, SARINS_ERROR, "parameter model_kind = '%s': cannot load the identifier model: model kind must "
                   "be 'hot' or 'cold'", kind);
        return SARINS_ERROR;
    }
    if (c->resources == NULL) {
        sarins_log(c, SARINS_ERROR, "parameter model_kind = '%s': cannot load the identifier model: no resources "
                   "folder (%s); give model_file", kind, c->resources_problem ? c->resources_problem : "unknown");
        return SARINS_ERROR;
    }
    if ((size_t)snprintf(path, n, "%s/axial_rbf_%s.bin", c->resources, kind) >= n) {
        sarins_log(c, SARINS_ERROR, "parameter model_kind = '%s': the resources path is too long", kind);
        return SARINS_ERROR;
    }
    return SARINS_OK;
}

static void ri_release(sarins_ctx *c)
{
    sarins_axial *a = c->work;
    if (a != NULL) {
        sarins_axial_release(a);
        free(a);
    }
    c->work = NULL;
}

/* Read and build the model into c->work; SARINS_ERROR naming the parameter, the file and the reason. */
static int load(sarins_ctx *c)
{
    char path[PATH_MAX_BYTES], msg[512];
    const char *param = "model_file", *value = "";
    if (model_path(c, path, sizeof path, &param, &value) != SARINS_OK)
        return SARINS_ERROR;
    unsigned char *buf = NULL;
    size_t n = 0;
    sarins_netfile f;
    sarins_axial *a = NULL;
    int code = sarins_netfile_read_path(path, &buf, &n, msg, sizeof msg);
    if (code == SARINS_NETFILE_OK)
        code = sarins_netfile_parse(buf, n, &f, msg, sizeof msg);
    if (code == SARINS_NETFILE_OK) {
        a = malloc(sizeof *a);
        code = a == NULL ? SARINS_NETFILE_MEMORY : sarins_axial_build(a, &f, msg, sizeof msg);
        if (a == NULL)
            snprintf(msg, sizeof msg, "out of memory");
    }
    free(buf);
    if (code != SARINS_NETFILE_OK) {
        if (a != NULL) {
            sarins_axial_release(a);
            free(a);
        }
        sarins_log(c, SARINS_ERROR, "parameter %s = '%s': cannot load the identifier model: model file '%s': %s",
                   param, value, path, msg);
        return SARINS_ERROR;
    }
    c->work = a;
    return SARINS_OK;
}

static int ri_initialize(sarins_ctx *c)
{
    memset(c->state, 0, sizeof(ri_state));
    c->r[SARINS_R_axial_drift] = 0.0;
    c->r[SARINS_R_apply_from] = 0.0;
    c->i[SARINS_I_identified] = 0;
    if (c->quiet)
        return SARINS_OK; /* the model is read when initialisation ends */
    if (check_parameters(c) != SARINS_OK)
        return SARINS_ERROR;
    return load(c);
}

static int ri_do_step(sarins_ctx *c, double t, double h)
{
    (void)t;
    ri_state *st = c->state;
    const sarins_axial *a = c->work;
    if (st->have_step && sm_fabs(h - st->step) > STEP_TOL * st->step) {
        sarins_log(c, SARINS_ERROR, "ValueError: communication step changed from %.17g s to %.17g s; this FMU needs a "
                   "fixed step", st->step, h);
        return SARINS_ERROR;
    }
    st->step = h;
    st->have_step = 1;
    if (a == NULL) {
        sarins_log(c, SARINS_ERROR, "no model loaded");
        return SARINS_ERROR;
    }
    if (c->i[SARINS_I_identified])
        return SARINS_OK;
    double nav = c->r[SARINS_R_nav_time], trigger = c->r[SARINS_R_trigger_time];
    if (sm_fabs(nav - trigger) <= TAG_TOL * h) {
        double drift_dph = 0.0;
        int status = sarins_axial_drift(a, c->r[SARINS_R_lat_error], c->r[SARINS_R_temperature],
                                        c->r[SARINS_R_temp_change], &drift_dph);
        if (status != SARINS_NET_OK) {
            sarins_log(c, SARINS_ERROR, "ValueError: %s (lat_error %.17g rad, temperature %.17g degC, temp_change "
                       "%.17g degC)", status == SARINS_NET_INPUT ? "identifier inputs are not all finite"
                                                                 : "the identified drift is not finite",
                       c->r[SARINS_R_lat_error], c->r[SARINS_R_temperature], c->r[SARINS_R_temp_change]);
            return SARINS_ERROR;
        }
        c->r[SARINS_R_axial_drift] = drift_dph * DPH_TO_RPS;
        c->i[SARINS_I_identified] = 1;
        c->r[SARINS_R_apply_from] = trigger + c->r[SARINS_R_latency];
    } else if (nav > trigger) {
        sarins_log(c, SARINS_ERROR, "ValueError: nav_time %.9g s passed trigger_time %.9g s without meeting it (put "
                   "the trigger on the communication grid)", nav, trigger);
        return SARINS_ERROR;
    }
    return SARINS_OK;
}

/* Every field of the state within what do_step relies on (model.h, State validation). */
static int ri_check_state(const sarins_ctx *c, int running)
{
    const ri_state *s = c->state;
    (void)running;
    /* the communication step: 0 before the first step, positive after */
    if (!sarins_state_int(c, "have_step", s->have_step, 0, 1)
        || !sarins_state_real(c, "step", s->step, s->have_step ? 1e-300 : 0.0, s->have_step ? 1e300 : 0.0))
        return SARINS_ERROR;
    return SARINS_OK;
}

const sarins_model sarins_model_desc = {
    .table = &SARINS_TABLE,
    .state_size = sizeof(ri_state),
    .state_version = 1,
    .check_state = ri_check_state,
    .initialize = ri_initialize,
    .do_step = ri_do_step,
    .release = ri_release,
};
