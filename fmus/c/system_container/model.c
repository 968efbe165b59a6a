/* SystemContainer: a whole system of FMI 2.0 co-simulation FMUs as one FMI 2.0 FMU, behind the shared glue
 * (model.h).  No Python, no JSON: the builder (orchestration/native_container.py) unzips every component FMU
 * into resources/<folder>/, writes the container's variable table (variables.h, compiled in) and a plain-text
 * plan, resources/container_plan.txt:
 *
 *   sarins-container-plan 1
 *   component NAME FOLDER MODEL_IDENTIFIER GUID      (one per component, index 0, 1, ... in this order)
 *   variable VR COMPONENT COMPONENT_VR PUSH          (one per container variable, VR 0, 1, ... in order)
 *   connection TYPE FROM FROM_VR TO TO_VR            (TYPE R, I, B or S; FROM/TO component indices)
 *   end
 *
 * Fields are separated by single spaces; names, folders and identifiers are [A-Za-z0-9_.-] (a folder not
 * starting with '.'), GUIDs printable without spaces.  A container variable maps to one variable of one
 * component, of the same type (an Enumeration is an Integer here); PUSH 1: the container applies its value
 * (start value, or what the host set) to the component before initialisation; inputs are applied again
 * before every step.  A variable with PUSH 0 is pushed only once the host has set it.
 *
 * Coupling: FMPy's container's (Jacobi).  At fmi2ExitInitializationMode (initialize()) each component is
 * loaded from resources/<folder>/binaries/<platform>/<identifier>.<so|dll>, instantiated with its own
 * resources URI, given its start values, fmi2SetupExperiment and fmi2EnterInitializationMode; then every
 * connection is copied (in plan order) while all are in Initialization Mode, then each leaves it.  Each
 * do_step(t, h): the inputs the host sets are applied, every component steps (plan order), then every
 * connection is copied and every exposed output read back into the container's variables.
 *
 * Everything is allocated in initialize() (the plan, the components, their instances); do_step never
 * allocates.  A bad plan is SARINS_ERROR naming its line, a component's failure SARINS_ERROR naming the
 * component; nothing outside the resources folder is opened (folders and identifiers are plain names).
 * FMU state is not supported (the components' states are not the container's to copy).
 */
#include "smath.h" /* first in every C file: the floating-point contract (the container copies values only) */

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2FunctionTypes.h"
#include "model.h"
#include "variables.h"

#ifdef _WIN32
#include <windows.h>
#define SC_PLATFORM "win64"
#define SC_EXT ".dll"
#else
#include <dlfcn.h>
/* keep the binary loadable on glibc 2.17: bind the dl* functions to their oldest versions, not to the
 * GLIBC_2.34 ones a new glibc would pick */
#if defined(__GLIBC__) && defined(__x86_64__)
__asm__(".symver dlopen,dlopen@GLIBC_2.2.5");
__asm__(".symver dlsym,dlsym@GLIBC_2.2.5");
__asm__(".symver dlclose,dlclose@GLIBC_2.2.5");
__asm__(".symver dlerror,dlerror@GLIBC_2.2.5");
#elif defined(__GLIBC__) && defined(__aarch64__)
__asm__(".symver dlopen,dlopen@GLIBC_2.17");
__asm__(".symver dlsym,dlsym@GLIBC_2.17");
__asm__(".symver dlclose,dlclose@GLIBC_2.17");
__asm__(".symver dlerror,dlerror@GLIBC_2.17");
#endif
#if defined(__linux__) && defined(__x86_64__)
#define SC_PLATFORM "linux64"
#elif defined(__linux__) && defined(__aarch64__)
#define SC_PLATFORM "aarch64-linux"
#elif defined(__APPLE__)
#define SC_PLATFORM "darwin64"
#else
#define SC_PLATFORM "unknown"
#endif
#ifdef __APPLE__
#define SC_EXT ".dylib"
#else
#define SC_EXT ".so"
#endif
#endif

#define SC_PLAN "container_plan.txt"
#define SC_PLAN_MAX (16L * 1024 * 1024) /* bytes: a larger plan is refused */
#define SC_NAME_MAX 256                 /* bytes of a name, folder, identifier or GUID */
#define SC_PATH 8192                    /* bytes of a composed path or URI */

typedef struct sc_part sc_part;

typedef struct { /* one component's logger environment */
    const sarins_ctx *c;
    const char *name;
} sc_env;

struct sc_part {
    const char *name, *folder, *identifier, *guid; /* into the plan's text */
    void *lib;
    fmi2Component inst;
    int in_init, stepped;
    sc_env env;
    fmi2CallbackFunctions cb;
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter;
    fmi2ExitInitializationModeTYPE *exit_init;
    fmi2TerminateTYPE *terminate;
    fmi2DoStepTYPE *do_step;
    fmi2GetRealTYPE *get_r;
    fmi2GetIntegerTYPE *get_i;
    fmi2GetBooleanTYPE *get_b;
    fmi2GetStringTYPE *get_s;
    fmi2SetRealTYPE *set_r;
    fmi2SetIntegerTYPE *set_i;
    fmi2SetBooleanTYPE *set_b;
    fmi2SetStringTYPE *set_s;
};

typedef struct {
    unsigned part, vr; /* the component and its value reference */
    int push;
} sc_map;

typedef struct {
    int type;
    unsigned from, from_vr, to, to_vr;
} sc_link;

typedef struct {
    char *text; /* the plan, NUL-separated fields */
    sc_part *parts;
    size_t n_parts;
    sc_map *map; /* by container value reference */
    sc_link *links;
    size_t n_links;
    char *path; /* SC_PATH bytes: scratch for paths and URIs (initialize only) */
} sc_work;

typedef struct {
    int unused;
} sc_state;

/* ------------------------------------------------------------------ logging */

static void sc_logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                      fmi2String message, ...)
{
    const sc_env *e = (const sc_env *)env;
    char text[2048];
    va_list ap;
    (void)instance;
    (void)category;
    if (e == NULL || e->c == NULL)
        return;
    va_start(ap, message);
    if (message == NULL)
        text[0] = '\0';
    else
        (void)vsnprintf(text, sizeof text, message, ap);
    va_end(ap);
    int st = status == fmi2OK ? SARINS_OK : status == fmi2Warning ? SARINS_WARNING
             : status == fmi2Discard ? SARINS_DISCARD : SARINS_ERROR;
    sarins_log(e->c, st, "component %s: %s", e->name, text);
}

/* a component call's status: OK/Warning go on, anything else is an error naming the component and call */
static int sc_check(const sarins_ctx *c, const sc_part *p, const char *fn, fmi2Status st)
{
    if (st == fmi2OK || st == fmi2Warning)
        return 1;
    sarins_log(c, SARINS_ERROR, "component %s: %s returned status %d", p->name, fn, (int)st);
    return 0;
}

/* ---------------------------------------------------------------- the plan */

static int plain_name(const char *s, int folder)
{
    size_t n = strlen(s);
    if (n == 0 || n >= SC_NAME_MAX || (folder && s[0] == '.'))
        return 0;
    for (size_t k = 0; k < n; k++) {
        char ch = s[k];
        if (!((ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_'
              || ch == '.' || ch == '-'))
            return 0;
    }
    return 1;
}

static int plain_token(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n >= SC_NAME_MAX)
        return 0;
    for (size_t k = 0; k < n; k++)
        if ((unsigned char)s[k] <= ' ' || (unsigned char)s[k] >= 127)
            return 0;
    return 1;
}

/* an unsigned decimal below limit */
static int parse_index(const char *s, unsigned long limit, unsigned *out)
{
    unsigned long v = 0;
    if (*s == '\0' || strlen(s) > 10)
        return 0;
    for (; *s; s++) {
        if (*s < '0' || *s > '9')
            return 0;
        v = v * 10 + (unsigned long)(*s - '0');
    }
    if (v >= limit)
        return 0;
    *out = (unsigned)v;
    return 1;
}

/* split line into at most max fields at single spaces (in place); the count, or max + 1 when there are more */
static size_t split(char *line, char **fields, size_t max)
{
    size_t n = 0;
    char *p = line;
    while (1) {
        if (n == max)
            return max + 1;
        fields[n++] = p;
        char *sp = strchr(p, ' ');
        if (sp == NULL)
            return n;
        *sp = '\0';
        p = sp + 1;
    }
}

static int plan_error(const sarins_ctx *c, size_t line, const char *what)
{
    sarins_log(c, SARINS_ERROR, "resources/" SC_PLAN " line %llu: %s", (unsigned long long)line, what);
    return SARINS_ERROR;
}

static int read_plan(sarins_ctx *c, sc_work *w)
{
    if (c->resources == NULL) {
        sarins_log(c, SARINS_ERROR, "no resources folder (%s): the container's plan is there",
                   c->resources_problem ? c->resources_problem : "unknown");
        return SARINS_ERROR;
    }
    if ((size_t)snprintf(w->path, SC_PATH, "%s/%s", c->resources, SC_PLAN) >= SC_PATH) {
        sarins_log(c, SARINS_ERROR, "the resources path is too long");
        return SARINS_ERROR;
    }
    FILE *f = fopen(w->path, "rb");
    if (f == NULL) {
        sarins_log(c, SARINS_ERROR, "cannot open resources/" SC_PLAN);
        return SARINS_ERROR;
    }
    size_t cap = 65536, n = 0;
    char *text = malloc(cap);
    int ok = text != NULL;
    while (ok) {
        if (n + 1 >= cap) {
            if (cap >= (size_t)SC_PLAN_MAX) {
                sarins_log(c, SARINS_ERROR, "resources/" SC_PLAN " is larger than %ld bytes", SC_PLAN_MAX);
                ok = 0;
                break;
            }
            char *more = realloc(text, cap * 2);
            if (more == NULL) {
                ok = 0;
                sarins_log(c, SARINS_ERROR, "out of memory reading the plan");
                break;
            }
            text = more;
            cap *= 2;
        }
        size_t got = fread(text + n, 1, cap - 1 - n, f);
        n += got;
        if (got == 0) {
            if (ferror(f)) {
                sarins_log(c, SARINS_ERROR, "cannot read resources/" SC_PLAN);
                ok = 0;
            }
            break;
        }
    }
    fclose(f);
    if (!ok) {
        free(text);
        return SARINS_ERROR;
    }
    if (text == NULL)
        return SARINS_ERROR;
    text[n] = '\0';
    if (strlen(text) != n) {
        free(text);
        return plan_error(c, 1, "a NUL byte in the plan");
    }
    w->text = text;
    return SARINS_OK;
}

static int resolve(sarins_ctx *c, sc_part *p, void **fn, const char *name)
{
#ifdef _WIN32
    FARPROC f = GetProcAddress((HMODULE)p->lib, name);
    memcpy(fn, &f, sizeof f < sizeof *fn ? sizeof f : sizeof *fn);
#else
    *fn = dlsym(p->lib, name);
#endif
    if (*fn == NULL) {
        sarins_log(c, SARINS_ERROR, "component %s: its binary has no function %s", p->name, name);
        return 0;
    }
    return 1;
}

#define RESOLVE(field, name) resolve(c, p, (void **)(void *)&p->field, name)

static int load_part(sarins_ctx *c, sc_work *w, sc_part *p)
{
    if ((size_t)snprintf(w->path, SC_PATH, "%s/%s/binaries/%s/%s%s", c->resources, p->folder, SC_PLATFORM,
                         p->identifier, SC_EXT) >= SC_PATH) {
        sarins_log(c, SARINS_ERROR, "component %s: the path of its binary is too long", p->name);
        return 0;
    }
#ifdef _WIN32
    for (char *q = w->path; *q; q++)
        if (*q == '/')
            *q = '\\';
    p->lib = (void *)LoadLibraryExA(w->path, NULL, LOAD_WITH_ALTERED_SEARCH_PATH);
    if (p->lib == NULL) {
        sarins_log(c, SARINS_ERROR, "component %s: cannot load %s (Windows error %lu)", p->name, w->path,
                   (unsigned long)GetLastError());
        return 0;
    }
#else
    p->lib = dlopen(w->path, RTLD_NOW | RTLD_LOCAL);
    if (p->lib == NULL) {
        const char *why = dlerror();
        sarins_log(c, SARINS_ERROR, "component %s: cannot load %s (%s)", p->name, w->path, why ? why : "?");
        return 0;
    }
#endif
    return RESOLVE(instantiate, "fmi2Instantiate") && RESOLVE(free_instance, "fmi2FreeInstance")
           && RESOLVE(setup, "fmi2SetupExperiment") && RESOLVE(enter, "fmi2EnterInitializationMode")
           && RESOLVE(exit_init, "fmi2ExitInitializationMode") && RESOLVE(terminate, "fmi2Terminate")
           && RESOLVE(do_step, "fmi2DoStep") && RESOLVE(get_r, "fmi2GetReal") && RESOLVE(get_i, "fmi2GetInteger")
           && RESOLVE(get_b, "fmi2GetBoolean") && RESOLVE(get_s, "fmi2GetString")
           && RESOLVE(set_r, "fmi2SetReal") && RESOLVE(set_i, "fmi2SetInteger")
           && RESOLVE(set_b, "fmi2SetBoolean") && RESOLVE(set_s, "fmi2SetString");
}

/* file: URI of resources/<folder>/resources (percent-encoded; file:///C:/... on Windows) into w->path */
static int part_uri(const sarins_ctx *c, sc_work *w, const sc_part *p)
{
    static const char hex[] = "0123456789ABCDEF";
    size_t k = 0;
    const char *pieces[4] = {c->resources, "/", p->folder, "/resources"};
    const char *head = "file://";
    size_t hn = strlen(head);
    if (hn + 1 >= SC_PATH)
        return 0;
    memcpy(w->path, head, hn);
    k = hn;
    if (c->resources[0] != '/')
        w->path[k++] = '/'; /* a drive letter: file:///C:/dir */
    for (int piece = 0; piece < 4; piece++) {
        for (const char *s = pieces[piece]; *s; s++) {
            unsigned char ch = (unsigned char)*s;
            if (ch == '\\')
                ch = '/';
            int plain = (ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9')
                        || ch == '/' || ch == '-' || ch == '_' || ch == '.' || ch == '~' || ch == ':';
            if (k + 4 >= SC_PATH)
                return 0;
            if (plain) {
                w->path[k++] = (char)ch;
            } else {
                w->path[k++] = '%';
                w->path[k++] = hex[ch >> 4];
                w->path[k++] = hex[ch & 15];
            }
        }
    }
    w->path[k] = '\0';
    return 1;
}

static int parse_plan(sarins_ctx *c, sc_work *w)
{
    const sarins_table *t = &SARINS_TABLE;
    /* count the lines of each kind first: the arrays are sized from them */
    size_t n_parts = 0, n_links = 0;
    for (char *line = w->text; *line;) {
        if (strncmp(line, "component ", 10) == 0)
            n_parts++;
        else if (strncmp(line, "connection ", 11) == 0)
            n_links++;
        char *nl = strchr(line, '\n');
        if (nl == NULL)
            break;
        line = nl + 1;
    }
    w->parts = calloc(n_parts ? n_parts : 1, sizeof *w->parts);
    w->map = calloc(t->n_vars ? t->n_vars : 1, sizeof *w->map);
    w->links = calloc(n_links ? n_links : 1, sizeof *w->links);
    if (w->parts == NULL || w->map == NULL || w->links == NULL) {
        sarins_log(c, SARINS_ERROR, "out of memory for the plan");
        return SARINS_ERROR;
    }
    size_t n_vars = 0, line_no = 0;
    int ended = 0;
    char *line = w->text;
    while (*line) {
        line_no++;
        char *nl = strchr(line, '\n');
        if (nl == NULL)
            return plan_error(c, line_no, "the last line does not end with a newline (truncated plan?)");
        *nl = '\0';
        if (nl > line && nl[-1] == '\r')
            nl[-1] = '\0';
        char *f[8] = {NULL}; /* (split sets f[0 .. nf - 1]; gcc -O3 cannot see it) */
        size_t nf = split(line, f, 7);
        if (ended)
            return plan_error(c, line_no, "text after 'end'");
        if (line_no == 1) {
            if (nf != 2 || strcmp(f[0], "sarins-container-plan") != 0 || strcmp(f[1], "1") != 0)
                return plan_error(c, line_no, "expected 'sarins-container-plan 1'");
        } else if (strcmp(f[0], "component") == 0) {
            if (nf != 5)
                return plan_error(c, line_no, "expected 'component NAME FOLDER MODEL_IDENTIFIER GUID'");
            if (w->n_parts > 0 && n_vars > 0)
                return plan_error(c, line_no, "a component after the variables");
            if (!plain_name(f[1], 0) || !plain_name(f[2], 1) || !plain_name(f[3], 1) || !plain_token(f[4]))
                return plan_error(c, line_no, "a name, folder or identifier that is not a plain name "
                                              "([A-Za-z0-9_.-], a folder not starting with '.'), or a bad GUID");
            for (size_t k = 0; k < w->n_parts; k++)
                if (strcmp(w->parts[k].folder, f[2]) == 0)
                    return plan_error(c, line_no, "a folder used by another component");
            sc_part *p = &w->parts[w->n_parts++];
            p->name = f[1];
            p->folder = f[2];
            p->identifier = f[3];
            p->guid = f[4];
        } else if (strcmp(f[0], "variable") == 0) {
            unsigned vr, part, cvr, push;
            if (nf != 5)
                return plan_error(c, line_no, "expected 'variable VR COMPONENT COMPONENT_VR PUSH'");
            if (!parse_index(f[1], t->n_vars, &vr) || vr != n_vars)
                return plan_error(c, line_no, "the variable's value reference is not the next one of the container");
            if (!parse_index(f[2], w->n_parts, &part))
                return plan_error(c, line_no, "no such component");
            if (!parse_index(f[3], 0xFFFFFFFFul, &cvr) || !parse_index(f[4], 2, &push))
                return plan_error(c, line_no, "a bad value reference or PUSH (0 or 1)");
            w->map[vr].part = part;
            w->map[vr].vr = cvr;
            w->map[vr].push = (int)push;
            n_vars++;
        } else if (strcmp(f[0], "connection") == 0) {
            sc_link *l = &w->links[w->n_links];
            const char *types = "RIBS";
            if (nf != 6)
                return plan_error(c, line_no, "expected 'connection TYPE FROM FROM_VR TO TO_VR'");
            if (strlen(f[1]) != 1 || strchr(types, f[1][0]) == NULL)
                return plan_error(c, line_no, "the type must be R, I, B or S");
            l->type = (int)(strchr(types, f[1][0]) - types);
            if (!parse_index(f[2], w->n_parts, &l->from) || !parse_index(f[4], w->n_parts, &l->to))
                return plan_error(c, line_no, "no such component");
            if (!parse_index(f[3], 0xFFFFFFFFul, &l->from_vr) || !parse_index(f[5], 0xFFFFFFFFul, &l->to_vr))
                return plan_error(c, line_no, "a bad value reference");
            w->n_links++;
        } else if (strcmp(f[0], "end") == 0 && nf == 1) {
            ended = 1;
        } else {
            return plan_error(c, line_no, "unknown line (component, variable, connection or end expected)");
        }
        line = nl + 1;
    }
    if (line_no == 0)
        return plan_error(c, 1, "expected 'sarins-container-plan 1' (the plan is empty)");
    if (!ended)
        return plan_error(c, line_no + 1, "no 'end' line (truncated plan?)");
    if (w->n_parts == 0)
        return plan_error(c, line_no, "no component");
    if (n_vars != t->n_vars)
        return plan_error(c, line_no, "the plan does not map every variable of the container");
    return SARINS_OK;
}

/* ------------------------------------------------------------- values */

/* the container variable k's value -> its component */
static int push_var(sarins_ctx *c, sc_work *w, size_t k)
{
    const sarins_var *v = &SARINS_TABLE.vars[k];
    sc_part *p = &w->parts[w->map[k].part];
    const fmi2ValueReference vr = w->map[k].vr;
    fmi2Status st;
    switch (v->type) {
    case SARINS_REAL: st = p->set_r(p->inst, &vr, 1, &c->r[v->slot]); break;
    case SARINS_INTEGER: st = p->set_i(p->inst, &vr, 1, &c->i[v->slot]); break;
    case SARINS_BOOLEAN: {
        fmi2Boolean b = c->b[v->slot] ? fmi2True : fmi2False;
        st = p->set_b(p->inst, &vr, 1, &b);
        break;
    }
    default: {
        fmi2String s = c->s[v->slot];
        st = p->set_s(p->inst, &vr, 1, &s);
        break;
    }
    }
    if (st == fmi2OK || st == fmi2Warning)
        return 1;
    sarins_log(c, SARINS_ERROR, "component %s: setting %s (its value reference %u) returned status %d", p->name,
               v->name, (unsigned)vr, (int)st);
    return 0;
}

/* a component's variable -> the container variable k (outputs) */
static int pull_var(sarins_ctx *c, sc_work *w, size_t k)
{
    const sarins_var *v = &SARINS_TABLE.vars[k];
    sc_part *p = &w->parts[w->map[k].part];
    const fmi2ValueReference vr = w->map[k].vr;
    fmi2Status st;
    switch (v->type) {
    case SARINS_REAL: st = p->get_r(p->inst, &vr, 1, &c->r[v->slot]); break;
    case SARINS_INTEGER: st = p->get_i(p->inst, &vr, 1, &c->i[v->slot]); break;
    case SARINS_BOOLEAN: {
        fmi2Boolean b = fmi2False;
        st = p->get_b(p->inst, &vr, 1, &b);
        c->b[v->slot] = b ? 1 : 0;
        break;
    }
    default: {
        fmi2String s = NULL;
        st = p->get_s(p->inst, &vr, 1, &s);
        if (st <= fmi2Warning) {
            size_t n = s ? strlen(s) : 0;
            if (n >= SARINS_STRING_MAX) {
                sarins_log(c, SARINS_ERROR, "component %s: String %s is longer than %d bytes", p->name, v->name,
                           SARINS_STRING_MAX - 1);
                return 0;
            }
            memcpy(c->s[v->slot], s ? s : "", n + 1);
        }
        break;
    }
    }
    if (st == fmi2OK || st == fmi2Warning)
        return 1;
    sarins_log(c, SARINS_ERROR, "component %s: getting %s (its value reference %u) returned status %d", p->name,
               v->name, (unsigned)vr, (int)st);
    return 0;
}

static int copy_link(sarins_ctx *c, sc_work *w, const sc_link *l)
{
    sc_part *a = &w->parts[l->from], *b = &w->parts[l->to];
    const fmi2ValueReference from = l->from_vr, to = l->to_vr;
    fmi2Status got, put = fmi2OK;
    switch (l->type) {
    case SARINS_REAL: {
        fmi2Real x = 0.0;
        got = a->get_r(a->inst, &from, 1, &x);
        if (got <= fmi2Warning)
            put = b->set_r(b->inst, &to, 1, &x);
        break;
    }
    case SARINS_INTEGER: {
        fmi2Integer x = 0;
        got = a->get_i(a->inst, &from, 1, &x);
        if (got <= fmi2Warning)
            put = b->set_i(b->inst, &to, 1, &x);
        break;
    }
    case SARINS_BOOLEAN: {
        fmi2Boolean x = fmi2False;
        got = a->get_b(a->inst, &from, 1, &x);
        if (got <= fmi2Warning)
            put = b->set_b(b->inst, &to, 1, &x);
        break;
    }
    default: {
        fmi2String x = NULL;
        got = a->get_s(a->inst, &from, 1, &x);
        if (got <= fmi2Warning)
            put = b->set_s(b->inst, &to, 1, &x);
        break;
    }
    }
    if (got > fmi2Warning || put > fmi2Warning) {
        sarins_log(c, SARINS_ERROR, "connection %s (value reference %u) -> %s (value reference %u): %s returned "
                   "status %d", a->name, (unsigned)from, b->name, (unsigned)to,
                   got > fmi2Warning ? "getting" : "setting", (int)(got > fmi2Warning ? got : put));
        return 0;
    }
    return 1;
}

static int copy_links(sarins_ctx *c, sc_work *w)
{
    for (size_t k = 0; k < w->n_links; k++)
        if (!copy_link(c, w, &w->links[k]))
            return 0;
    return 1;
}

static int pull_outputs(sarins_ctx *c, sc_work *w)
{
    for (size_t k = 0; k < SARINS_TABLE.n_vars; k++)
        if (SARINS_TABLE.vars[k].causality == SARINS_OUTPUT && !pull_var(c, w, k))
            return 0;
    return 1;
}

/* ------------------------------------------------------------- lifecycle */

static void sc_release(sarins_ctx *c)
{
    sc_work *w = c->work;
    if (w == NULL)
        return;
    for (size_t k = w->n_parts; k-- > 0;) { /* in reverse order */
        sc_part *p = &w->parts[k];
        if (p->inst != NULL && p->free_instance != NULL)
            p->free_instance(p->inst);
        p->inst = NULL;
        if (p->lib != NULL) {
#ifdef _WIN32
            FreeLibrary((HMODULE)p->lib);
#else
            dlclose(p->lib);
#endif
        }
        p->lib = NULL;
    }
    free(w->parts);
    free(w->map);
    free(w->links);
    free(w->path);
    free(w->text);
    free(w);
    c->work = NULL;
}

static int start_parts(sarins_ctx *c, sc_work *w)
{
    for (size_t k = 0; k < w->n_parts; k++) {
        sc_part *p = &w->parts[k];
        if (!load_part(c, w, p))
            return 0;
        if (!part_uri(c, w, p)) {
            sarins_log(c, SARINS_ERROR, "component %s: its resources URI is too long", p->name);
            return 0;
        }
        p->env.c = c;
        p->env.name = p->name;
        p->cb.logger = sc_logger;
        p->cb.allocateMemory = calloc;
        p->cb.freeMemory = free;
        p->cb.stepFinished = NULL;
        p->cb.componentEnvironment = &p->env;
        p->inst = p->instantiate(p->name, fmi2CoSimulation, p->guid, w->path, &p->cb, fmi2False, fmi2False);
        if (p->inst == NULL) {
            sarins_log(c, SARINS_ERROR, "component %s: fmi2Instantiate failed", p->name);
            return 0;
        }
    }
    /* start values and what the host set, in the container's variable order (FMPy's container applies its
     * start values at instantiation, the host's values as they come) */
    for (size_t k = 0; k < SARINS_TABLE.n_vars; k++) {
        const sarins_var *v = &SARINS_TABLE.vars[k];
        if (v->causality != SARINS_OUTPUT && (w->map[k].push || c->set[k]) && !push_var(c, w, k))
            return 0;
    }
    for (size_t k = 0; k < w->n_parts; k++) {
        sc_part *p = &w->parts[k];
        if (!sc_check(c, p, "fmi2SetupExperiment", p->setup(p->inst, fmi2False, 0.0, c->start_time, fmi2False, 0.0)))
            return 0;
    }
    for (size_t k = 0; k < w->n_parts; k++) {
        sc_part *p = &w->parts[k];
        if (!sc_check(c, p, "fmi2EnterInitializationMode", p->enter(p->inst)))
            return 0;
        p->in_init = 1;
    }
    if (!copy_links(c, w))
        return 0;
    for (size_t k = 0; k < w->n_parts; k++) {
        sc_part *p = &w->parts[k];
        if (!sc_check(c, p, "fmi2ExitInitializationMode", p->exit_init(p->inst)))
            return 0;
        p->in_init = 0;
    }
    return pull_outputs(c, w);
}

static int sc_initialize(sarins_ctx *c)
{
    if (c->quiet)
        return SARINS_OK; /* the components start when initialisation mode ends: outputs stay at their starts */
    sc_work *w = calloc(1, sizeof *w);
    if (w == NULL) {
        sarins_log(c, SARINS_ERROR, "out of memory");
        return SARINS_ERROR;
    }
    c->work = w;
    w->path = malloc(SC_PATH);
    if (w->path == NULL) {
        sarins_log(c, SARINS_ERROR, "out of memory");
        sc_release(c);
        return SARINS_ERROR;
    }
    if (read_plan(c, w) != SARINS_OK || parse_plan(c, w) != SARINS_OK || !start_parts(c, w)) {
        sc_release(c);
        return SARINS_ERROR;
    }
    return SARINS_OK;
}

static int sc_do_step(sarins_ctx *c, double t, double h)
{
    sc_work *w = c->work;
    if (w == NULL) {
        sarins_log(c, SARINS_ERROR, "the components are not running");
        return SARINS_ERROR;
    }
    for (size_t k = 0; k < SARINS_TABLE.n_vars; k++) {
        const sarins_var *v = &SARINS_TABLE.vars[k];
        int again = v->causality == SARINS_INPUT ? (w->map[k].push || c->set[k])
                    : (v->causality == SARINS_PARAMETER && v->variability == SARINS_TUNABLE && c->set[k]);
        if (again && !push_var(c, w, k))
            return SARINS_ERROR;
    }
    for (size_t k = 0; k < w->n_parts; k++) {
        sc_part *p = &w->parts[k];
        fmi2Status st = p->do_step(p->inst, t, h, fmi2True);
        if (st == fmi2Discard) {
            sarins_log(c, SARINS_DISCARD, "component %s: fmi2DoStep(%.17g, %.17g) discarded the step", p->name, t, h);
            return SARINS_DISCARD;
        }
        if (!sc_check(c, p, "fmi2DoStep", st))
            return SARINS_ERROR;
    }
    if (!copy_links(c, w) || !pull_outputs(c, w))
        return SARINS_ERROR;
    return SARINS_OK;
}

static void sc_terminate(sarins_ctx *c)
{
    sc_work *w = c->work;
    if (w == NULL)
        return;
    for (size_t k = 0; k < w->n_parts; k++) {
        sc_part *p = &w->parts[k];
        if (p->inst != NULL)
            (void)sc_check(c, p, "fmi2Terminate", p->terminate(p->inst));
    }
}

const sarins_model sarins_model_desc = {
    .table = &SARINS_TABLE,
    .state_size = sizeof(sc_state),
    .state_version = 1,
    .initialize = sc_initialize,
    .do_step = sc_do_step,
    .release = sc_release,
    .terminate = sc_terminate,
    .no_fmu_state = 1,
};
