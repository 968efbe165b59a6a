/* The part of the FMI glue that does not depend on the FMI version (fmus/c/glue_core.c), shared by
 * fmi2_glue.c (FMI 2.0) and fmi3_glue.c (FMI 3.0).  Internal to the glue: models see model.h only.
 *
 * It owns the instance (struct sarins_glue), the logger and its categories, the value arrays and their
 * start values, value-reference/type/causality checks, the model callbacks' statuses, the step-time
 * checks and the FMU state blob.  Statuses are SARINS_OK .. SARINS_ERROR, numerically the fmi2Status and
 * fmi3Status values.  A version file embeds sarins_glue as the first member of its own instance struct
 * (the logger callback and its environment), sets emit, and maps its calls onto the sg_* functions.
 */
#ifndef SARINS_GLUE_CORE_H
#define SARINS_GLUE_CORE_H

#include <stddef.h>

#include "model.h"

/* instance states: the union of FMI 2.0 (section 4.2.4) and FMI 3.0 co-simulation (section 4.2) */
enum {
    S_INSTANTIATED = 1, S_INIT = 2, S_STEP_COMPLETE = 4, /* FMI 3.0: Step Mode */
    S_STEP_FAILED = 8,                                   /* FMI 2.0 stepFailed; FMI 3.0 after a discarded step */
    S_TERMINATED = 16, S_ERROR = 32,
    S_CONFIG = 64,   /* FMI 3.0 Configuration Mode (from Instantiated) */
    S_RECONFIG = 128 /* FMI 3.0 Reconfiguration Mode (from Step Mode) */
};
#define RUN_STATES (S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED)
#define SG_ANY_STATE (S_INSTANTIATED | S_INIT | RUN_STATES | S_ERROR | S_CONFIG | S_RECONFIG)
#define SG_FMU_STATE_STATES (S_INSTANTIATED | S_INIT | RUN_STATES)

#define SG_NO_TIME_VR 0xFFFFFFFFu

struct sarins_glue {
    const sarins_model *model;
    const sarins_table *table;
    char *name;
    /* hands one formatted message to the host's logger (set by the version file) */
    void (*emit)(const sarins_glue *g, int status, const char *category, const char *text);
    const char *prefix;   /* "fmi2" or "fmi3": function names in messages */
    const char *standard; /* "FMI 2.0 section 4.2.4": cited for a call out of order */
    unsigned time_vr;     /* FMI 3.0: the independent variable time (a read-only Real); else SG_NO_TIME_VR */
    int state;
    int *cat_on;
    const sarins_var **by_vr; /* value reference -> variable (NULL: none) */
    size_t n_vr;
    const sarins_var **outputs; /* the Real outputs in table order (sg_check_outputs after every step) */
    size_t n_outputs;
    unsigned char *values; /* the value arrays, one block: r, i, b, s */
    unsigned char *built;  /* the value block as initialize() last saw it (its parameters built c->work) */
    size_t values_size;
    double built_start;
    int have_built;
    sarins_ctx ctx;
    int have_time;
    double t_next;
    unsigned long problems; /* messages logged with status >= Discard (so a failure is never silent) */
    int arrays_visible;     /* FMI 3.0: array variables have value references (FMI 2.0: unknown there) */
    char *resources;        /* the resources folder (ctx.resources), owned */
    double *array_block;    /* every array's elements, one block */
    size_t array_doubles;   /* its length */
    size_t *array_len;      /* by SARINS_A_* slot: the elements allocated for that array (what every access is
                             * bounded by; a structural parameter set since then takes effect when the arrays
                             * are next sized) */
    void **states;          /* the FMU states this instance issued and has not freed (recognised by address) */
    size_t n_states, cap_states;
};

#if defined(__GNUC__)
#define SG_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define SG_PRINTF(f, a)
#endif

void sg_log(sarins_glue *g, int status, const char *fmt, ...) SG_PRINTF(3, 4);
/* Log an error, put the instance in the error state, return SARINS_ERROR. */
int sg_fail(sarins_glue *g, const char *fmt, ...) SG_PRINTF(2, 3);
int sg_bad_state(sarins_glue *g, const char *fn);

/* in an fmiXStatus function: the instance exists and is in one of the allowed states (the int converts to
 * the version's status type, whose values SARINS_* are) */
#define SG_REQUIRE(g, fn, allowed)                                                                           \
    do {                                                                                                     \
        if ((g) == NULL)                                                                                     \
            return (int)SARINS_ERROR;                                                                        \
        if (!((g)->state & (allowed)))                                                                       \
            return sg_bad_state((g), (fn));                                                                  \
    } while (0)

/* Instances: sg_alloc(size of the version's struct) zeroes it; the caller sets emit, prefix, standard,
 * time_vr and its logger, then sg_init checks the name and token and allocates (0 on failure, logged). */
sarins_glue *sg_alloc(size_t size);
int sg_init(sarins_glue *g, const char *instance_name, const char *token, int logging_on, const char *fn);
/* The resources folder for c->resources: is_uri 1 for FMI 2.0's fmuResourceLocation (a file: URI), 0 for FMI
 * 3.0's resourcePath (a path).  A missing or unusable location is not an error here (most models need none):
 * c->resources stays NULL and c->resources_problem says why.  Returns 0 only when out of memory (logged). */
int sg_set_resources(sarins_glue *g, const char *location, int is_uri);
void sg_free(sarins_glue *g);

int sg_set_debug_logging(sarins_glue *g, int on, size_t n, const char *const categories[], const char *fn);
int sg_model_status(sarins_glue *g, int status, unsigned long problems_before, const char *fn);
int sg_check_outputs(sarins_glue *g, const char *fn);
/* (Re)size the arrays from the structural parameters (allocates when a length changed; each in
 * 1 .. max_dim, else SARINS_ERROR with the reason).  Called at instantiation, at the end of Configuration
 * Mode, before initialize() and at set-state. */
int sg_size_arrays(sarins_glue *g, const char *fn);
/* elements of a variable: 1 for a scalar, the elements allocated for an array (its structural parameter's
 * value once the arrays were sized) */
size_t sg_length(const sarins_glue *g, const sarins_var *v);
/* 0 (logged error, error state) when v is an array whose structural parameter was set to another length
 * than the one allocated (Configuration Mode not left yet, or a refused value): it cannot be read or set. */
int sg_array_usable(sarins_glue *g, const char *fn, const sarins_var *v);
/* the number of values for these value references (arrays: their lengths); 0 and a logged error if n_values
 * differs */
int sg_check_count(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, size_t n_values);

/* Lifecycle steps shared by both versions (the caller has checked the state). */
void sg_enter_init(sarins_glue *g);
int sg_exit_init(sarins_glue *g, const char *fn);
void sg_terminate(sarins_glue *g);
void sg_reset(sarins_glue *g);
int sg_do_step(sarins_glue *g, double t, double h, const char *fn);
double sg_time(const sarins_glue *g); /* s: the current communication point */

/* Values.  `settable` is the instance's rule for its state (sg_settable_default: FMI 2.0's). Every value
 * reference is checked before any value moves, so a refused call changes nothing. */
typedef int (*sg_settable_fn)(const sarins_glue *g, const sarins_var *v);
int sg_settable_default(const sarins_glue *g, const sarins_var *v);
int sg_check_args(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, const void *values, int type,
                  sg_settable_fn settable);
int sg_get_real(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, double value[]);
int sg_get_int(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, int value[]);
int sg_get_string(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, const char *value[]);
int sg_set_real(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, const double value[],
                sg_settable_fn settable);
int sg_set_int(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, const int value[],
               sg_settable_fn settable);
int sg_set_string(sarins_glue *g, const char *fn, const unsigned vr[], size_t n, const char *const value[],
                  sg_settable_fn settable);

/* FMU state: one self-describing blob, the same bytes in memory and serialized. */
int sg_get_state(sarins_glue *g, void **state, const char *fn);
int sg_set_state(sarins_glue *g, const void *state, const char *fn);
int sg_free_state(sarins_glue *g, void **state, const char *fn);
/* free every state the instance issued and still holds (at sg_free) */
void sg_free_states(sarins_glue *g);
int sg_state_size(sarins_glue *g, const void *state, size_t *size, const char *fn);
int sg_serialize(sarins_glue *g, const void *state, unsigned char *dst, size_t size, const char *fn);
int sg_deserialize(sarins_glue *g, const unsigned char *src, size_t size, void **state, const char *fn);

#endif
