/* Interface between one native model (fmus/c/<model>/model.c) and the shared FMI 2.0 glue (fmus/c/fmi2_glue.c).
 *
 * The glue answers every FMI 2.0 co-simulation call and owns the instance: the state machine (FMI 2.0
 * section 4.2.4), the logger and its categories, value-reference/type/causality checks, the time (the first
 * step starts at fmi2SetupExperiment's start time, each next one where the previous ended), the check that
 * no Real output is non-finite after a callback returned SARINS_OK, and FMU state.  A model only sees a
 * sarins_ctx; it never includes the FMI headers.
 *
 * Variables.  fmus/build.py generates "variables.h" for each model from its one declaration (the slave
 * class): `static const sarins_table SARINS_TABLE` (identifier, GUID, log categories, every variable with
 * value reference, type, causality, variability and start value) and, per variable, its slot in the array
 * of its type: SARINS_R_<name> (Real), SARINS_I_<name> (Integer), SARINS_B_<name> (Boolean),
 * SARINS_S_<name> (String).  Value references and slots never change between builds unless the declaration
 * does.  The model reads and writes values only through the ctx arrays: c->r[SARINS_R_rate].
 *
 * Memory.  The glue allocates the value arrays and the model's state (state_size bytes, zeroed) at
 * fmi2Instantiate; it sets start values there and at fmi2Reset.  Strings live in fixed buffers of
 * SARINS_STRING_MAX bytes (a longer fmi2SetString value is refused with fmi2Error).  The model allocates
 * what its parameters require (schedules, tables: c->work) in initialize() only; do_step never allocates.
 *
 * Callbacks (every one is called with a valid ctx; status returns are SARINS_OK/DISCARD/ERROR):
 *   initialize(c): check every parameter (a bad one: sarins_log(c, SARINS_ERROR, "parameter x = .. must ..")
 *       and return SARINS_ERROR, having freed what it allocated), then build c->work (release() is called
 *       first by the glue, so c->work is NULL on entry), reset c->state to the start of a run, and write
 *       the outputs at c->start_time.  Called at fmi2ExitInitializationMode, at fmi2EnterInitializationMode
 *       with c->quiet = 1 (outputs during initialisation; a failure there is silent and not an error, the
 *       parameters may still change), and by fmi2SetFMUstate when the restored parameters differ from those
 *       c->work was built from (the glue then restores values and state over what initialize wrote).
 *   do_step(c, t, h): the step from communication point t (s) of size h (s, > 0, finite, checked by the
 *       glue): read inputs and parameters from the arrays, write outputs; SARINS_OK, SARINS_DISCARD or
 *       SARINS_ERROR, each non-OK with a logged reason.  Never allocates, never does I/O.
 *   release(c): free c->work (may be NULL) and set it to NULL.  At reset, free, before initialize.
 *   terminate(c): optional (NULL: nothing to do).
 *
 * FMU state.  Everything that changes during a run is in the value arrays, in c->state (plain bytes, no
 * pointers: copied as is, also into another process) and, only if the model keeps mutable data in c->work,
 * in the optional work-state callbacks: work_state_size(c) its fixed size once initialized, save_work_state
 * writes it, load_work_state reads it back (SARINS_ERROR with a logged reason if it does not fit).  Data in
 * c->work that is a function of the parameters only (a schedule) is not part of the state.  state_version
 * goes into serialized states: change it whenever the layout of c->state or of the work state changes.
 *
 * State validation.  A state handed to the FMU (fmi2SetFMUstate / fmi3SetFMUState, and every deserialised
 * blob) is checked before any of it is used: its structure (sizes, GUID, versions, checksum), then the glue's
 * fields (FMI state known, have_time 0/1, communication point and start time finite and in order, Booleans
 * and set flags 0/1, Strings terminated in their buffers, after initialisation every scalar Real output
 * finite), then the model's optional check_state(c, running): c is a view of the blob's values and model
 * state (c->state a copy, aligned; c->work and c->a are NULL: check what the state alone must satisfy) and
 * running is 1 when the state is after initialisation.  It checks every field of c->state against the
 * invariants do_step relies on (finite numbers, enums in range, counts and indices within their buffers,
 * the communication step 0 before the first step and positive after) and returns SARINS_OK, or
 * SARINS_ERROR with the field named (sarins_log).  A refused state changes nothing in the instance; a
 * work state is checked by load_work_state against the rebuilt work.
 *
 * Recovery.  After an error (the instance in the error state), fmi2SetFMUstate / fmi3SetFMUState to a state
 * saved earlier is allowed (FMI 2.0.x, 3.0): the glue rebuilds the model's work from the state's parameters
 * (initialize()), then restores values, state, work state and arrays; the run continues bit for bit as from
 * the moment the state was saved.
 *
 * Set flags.  c->set[vr] (by value reference; the table's variables are numbered 0, 1, ... in that order)
 * is 1 once the host has set the variable with an fmi2Set* call since fmi2Instantiate or the last
 * fmi2Reset, else 0 (a start value is not "set").  A model uses it where the declaration says that setting
 * a parameter changes its meaning ("a coefficient that is set overrides the preset").  The flags travel
 * with the values: they are in the FMU state and compared like values when fmi2SetFMUstate decides whether
 * initialize() must rebuild c->work.
 *
 * Arrays (FMI 3.0).  A declaration may add Real array variables whose length is a structural parameter (an
 * Integer, causality SARINS_STRUCTURAL_PARAMETER, 1 .. table->max_dim): variables.h then defines
 * SARINS_A_<name> slots, and c->a[SARINS_A_<name>] holds c->i[SARINS_I_<n>] doubles.  The glue allocates
 * the arrays (at instantiation, when Configuration Mode ends, before every initialize(), at
 * fmi3SetFMUState), zeroes them, checks the structural parameters (a value out of range is an error with
 * the reason) and keeps the arrays in the FMU state; do_step reads array inputs and writes array outputs in
 * place, never allocating; output arrays are checked finite like scalar outputs.  The FMI 2.0 variant has
 * no arrays (their value references are unknown there; c->a[k] still exists, sized by the parameter, so a
 * model needs no #ifdef) and its structural parameters are fixed Integer parameters.
 *
 * Resources.  c->resources is the FMU's resources folder as a local path (set at instantiation, constant
 * for the instance's life), for a model that reads data files at initialize() (a trained network); never
 * read or write anything outside it and the files its parameters name.
 *
 * No globals: the descriptor is const data, every mutable thing is per instance; instances are
 * independent and may run in different threads.
 */
#ifndef SARINS_MODEL_H
#define SARINS_MODEL_H

#include <stddef.h>
#include <stdint.h>

#define SARINS_STRING_MAX 4096 /* bytes of a String variable's buffer, terminating NUL included (Linux PATH_MAX) */

enum { SARINS_OK = 0, SARINS_WARNING = 1, SARINS_DISCARD = 2, SARINS_ERROR = 3 }; /* = fmi2Status values */
enum { SARINS_REAL = 0, SARINS_INTEGER = 1, SARINS_BOOLEAN = 2, SARINS_STRING = 3 };
enum { SARINS_PARAMETER = 0, SARINS_CALCULATED_PARAMETER = 1, SARINS_INPUT = 2, SARINS_OUTPUT = 3,
       SARINS_LOCAL = 4, SARINS_INDEPENDENT = 5,
       SARINS_STRUCTURAL_PARAMETER = 6 /* an Integer sizing arrays: FMI 3.0 structuralParameter (UInt64),
                                        * FMI 2.0 a fixed Integer parameter */ };
enum { SARINS_CONSTANT = 0, SARINS_FIXED = 1, SARINS_TUNABLE = 2, SARINS_DISCRETE = 3, SARINS_CONTINUOUS = 4 };

typedef struct {
    const char *name;
    unsigned vr;              /* value reference (modelDescription.xml) */
    unsigned char type;       /* SARINS_REAL .. SARINS_STRING */
    unsigned char causality;  /* SARINS_PARAMETER .. */
    unsigned char variability; /* SARINS_CONSTANT .. */
    unsigned slot;            /* index into the array of its type */
    double start_real;        /* start value of a Real */
    int start_int;            /* start value of an Integer or Boolean (0/1) */
    const char *start_string; /* start value of a String, else NULL */
    int dim;                  /* -1: a scalar; else a Real array (FMI 3.0 only) whose length is the Integer
                               * c->i[dim] (a structural parameter) and slot its SARINS_A_* index */
} sarins_var;

typedef struct {
    const char *identifier; /* modelIdentifier */
    const char *guid;       /* fmi2Instantiate's GUID must equal it */
    const sarins_var *vars; /* in value-reference order */
    size_t n_vars;
    size_t n_real, n_integer, n_boolean, n_string; /* sizes of the value arrays */
    const char *const *categories;                  /* log categories of modelDescription.xml */
    size_t n_categories;
    size_t n_array; /* Real array variables (SARINS_A_* slots) */
    int max_dim;    /* largest value a structural parameter may take (arrays: 1 .. max_dim elements) */
} sarins_table;

typedef struct sarins_glue sarins_glue; /* the glue's instance, opaque to models */

typedef struct {
    double *r;                       /* Reals, by SARINS_R_* slot */
    int *i;                          /* Integers, by SARINS_I_* slot */
    int *b;                          /* Booleans (0/1), by SARINS_B_* slot */
    char (*s)[SARINS_STRING_MAX];    /* Strings, NUL-terminated, by SARINS_S_* slot */
    void *state;                     /* state_size bytes, plain data, zeroed at instantiation and reset */
    void *work;                      /* the model's own allocations (initialize), NULL before */
    double start_time;               /* s: fmi2SetupExperiment's start time (0 if it was not called) */
    int quiet;                       /* 1 during the initialize() call of fmi2EnterInitializationMode */
    sarins_glue *glue;
    unsigned char *set;              /* set[vr] = 1 once the host set variable vr (any fmi2Set*) since
                                      * instantiation or the last reset; see "Set flags" above */
    double **a;                      /* Real arrays, by SARINS_A_* slot: c->a[k][0 .. c->i[dim] - 1] */
    const char *resources;           /* local path of the FMU's resources folder, no trailing separator
                                      * (from fmi2Instantiate's file: URI or fmi3's resourcePath), or NULL;
                                      * then resources_problem says why */
    const char *resources_problem;   /* NULL, or why there is no resources path (for the model's message) */
} sarins_ctx;

typedef struct {
    const sarins_table *table;
    size_t state_size;
    uint32_t state_version;
    int (*initialize)(sarins_ctx *c);
    int (*do_step)(sarins_ctx *c, double t, double h);
    void (*release)(sarins_ctx *c);
    void (*terminate)(sarins_ctx *c);                  /* optional */
    size_t (*work_state_size)(const sarins_ctx *c);    /* optional, with the next two */
    void (*save_work_state)(const sarins_ctx *c, unsigned char *dst);
    int (*load_work_state)(sarins_ctx *c, const unsigned char *src, size_t n);
    int (*check_state)(const sarins_ctx *c, int running); /* optional: see "State validation" above */
    int no_fmu_state; /* 1: FMU state is not supported (canGetAndSetFMUstate false): getting, setting and
                       * deserialising a state is an error with the reason (a model whose state is not its
                       * own to copy, such as the system container) */
} sarins_model;

/* Each model.c defines exactly this one object. */
extern const sarins_model sarins_model_desc;

/* Log a message to the host (implemented by the glue).  status SARINS_OK/WARNING reach the host when debug
 * logging is on for its category ("logAll" for OK, "logStatusWarning" for WARNING); DISCARD and ERROR always
 * do.  Nothing is logged during a quiet initialize() (c->quiet).  Never allocates.  Formats: C99 printf,
 * but no %zu (mingw-w64 checks against msvcrt): cast sizes to unsigned long long and use %llu. */
void sarins_log(const sarins_ctx *c, int status, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* For check_state (implemented by the glue): 1 when the state's field x is finite and in lo .. hi, else the
 * field named in a logged error ("the state's <field> = <x> is not ...") and 0. */
int sarins_state_real(const sarins_ctx *c, const char *field, double x, double lo, double hi);
int sarins_state_int(const sarins_ctx *c, const char *field, long long x, long long lo, long long hi);
/* the same for n doubles: every one finite (no range) */
int sarins_state_finite(const sarins_ctx *c, const char *field, const double *x, size_t n);

/* 1 when the host can reach the array variables (FMI 3.0), 0 when it cannot (FMI 2.0: c->a still exists, but
 * an array input is never set there, so a model that needs one refuses its parameters). */
int sarins_arrays_visible(const sarins_ctx *c);

/* The Integer parameter `name` (value) choosing between 0 (`zero`, what it means) and 1 (read the *_sub array
 * inputs): SARINS_OK, or SARINS_ERROR with the reason logged (another value; 1 where the arrays are not
 * visible). */
int sarins_check_sub_switch(const sarins_ctx *c, const char *name, int value, const char *zero);

#endif
