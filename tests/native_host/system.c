/* A native FMI 2.0 co-simulation master for the tests: several FMUs, fixed
 * step, Gauss-Seidel in the order given, no Python in the process.
 *
 * usage: system PLAN_FILE
 * PLAN_FILE lines (whitespace separated, one item per line):
 *   steps N STEP_SIZE
 *   fmu UNZIPPED_DIR MODEL_IDENTIFIER GUID          (index = order of appearance)
 *   real FMU VR VALUE | int FMU VR VALUE | string FMU VR TEXT   (start values)
 *   link SRC_FMU SRC_VR DST_FMU DST_VR              (Real output -> Real input)
 *   print FMU VR                                    (Real printed after the last step)
 * Inputs are set from their sources before each FMU leaves initialisation and
 * before each FMU's doStep.  Prints "STATUS <fmu> <function> <status>" for
 * every non-OK call, "VALUE <fmu> <vr> <value>" and "DONE <steps>"; exits 0
 * when the run completed, 1 when a call failed, 2 on a usage/loading error.
 */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define MAXF 8
#define MAXL 64

typedef struct {
    void *lib;
    fmi2Component c;
    fmi2InstantiateTYPE *instantiate;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter;
    fmi2ExitInitializationModeTYPE *exit_;
    fmi2DoStepTYPE *step;
    fmi2TerminateTYPE *terminate;
    fmi2FreeInstanceTYPE *free_;
    fmi2SetRealTYPE *setReal;
    fmi2GetRealTYPE *getReal;
    fmi2SetIntegerTYPE *setInteger;
    fmi2SetStringTYPE *setString;
} Fmu;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env;
    if (status == fmi2OK) return;
    va_list ap;
    va_start(ap, message);
    printf("LOG %s %d %s: ", name ? name : "", (int)status, category ? category : "");
    vprintf(message, ap);
    printf("\n");
    va_end(ap);
}

static int check(int k, const char *fn, fmi2Status st) {
    if (st != fmi2OK) {
        printf("STATUS %d %s %d\n", k, fn, (int)st);
        return 0;
    }
    return 1;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: system PLAN_FILE\n");
        return 2;
    }
    FILE *plan = fopen(argv[1], "r");
    if (!plan) {
        perror(argv[1]);
        return 2;
    }
    Fmu f[MAXF];
    int nf = 0, nl = 0, np = 0;
    int link[MAXL][4], printed[MAXL][2];
    long steps = 0;
    double h = 1.0;
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    char kind[32];
    while (fscanf(plan, "%31s", kind) == 1) {
        if (strcmp(kind, "steps") == 0) {
            if (fscanf(plan, "%ld %lf", &steps, &h) != 2) return 2;
        } else if (strcmp(kind, "fmu") == 0) {
            char dir[2048], model[256], guid[256], path[4096], uri[4096], name[32];
            if (nf == MAXF || fscanf(plan, "%2047s %255s %255s", dir, model, guid) != 3) return 2;
            Fmu *u = &f[nf];
            snprintf(path, sizeof path, "%s/binaries/linux64/%s.so", dir, model);
            u->lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
            if (!u->lib) {
                fprintf(stderr, "%s\n", dlerror());
                return 2;
            }
            u->instantiate = (fmi2InstantiateTYPE *)dlsym(u->lib, "fmi2Instantiate");
            u->setup = (fmi2SetupExperimentTYPE *)dlsym(u->lib, "fmi2SetupExperiment");
            u->enter = (fmi2EnterInitializationModeTYPE *)dlsym(u->lib, "fmi2EnterInitializationMode");
            u->exit_ = (fmi2ExitInitializationModeTYPE *)dlsym(u->lib, "fmi2ExitInitializationMode");
            u->step = (fmi2DoStepTYPE *)dlsym(u->lib, "fmi2DoStep");
            u->terminate = (fmi2TerminateTYPE *)dlsym(u->lib, "fmi2Terminate");
            u->free_ = (fmi2FreeInstanceTYPE *)dlsym(u->lib, "fmi2FreeInstance");
            u->setReal = (fmi2SetRealTYPE *)dlsym(u->lib, "fmi2SetReal");
            u->getReal = (fmi2GetRealTYPE *)dlsym(u->lib, "fmi2GetReal");
            u->setInteger = (fmi2SetIntegerTYPE *)dlsym(u->lib, "fmi2SetInteger");
            u->setString = (fmi2SetStringTYPE *)dlsym(u->lib, "fmi2SetString");
            snprintf(uri, sizeof uri, "file://%s/resources", dir);
            snprintf(name, sizeof name, "fmu%d", nf);
            u->c = u->instantiate(name, fmi2CoSimulation, guid, uri, &cb, fmi2False, fmi2False);
            if (!u->c) {
                printf("STATUS %d fmi2Instantiate NULL\n", nf);
                return 1;
            }
            if (!check(nf, "fmi2SetupExperiment", u->setup(u->c, fmi2False, 0.0, 0.0, fmi2False, 0.0))) return 1;
            nf++;
        } else if (strcmp(kind, "real") == 0 || strcmp(kind, "int") == 0 || strcmp(kind, "string") == 0) {
            int k;
            unsigned vr;
            char text[1024];
            if (fscanf(plan, "%d %u %1023s", &k, &vr, text) != 3 || k >= nf) return 2;
            fmi2ValueReference r = vr;
            fmi2Status st;
            if (kind[0] == 'r') {
                fmi2Real v = atof(text);
                st = f[k].setReal(f[k].c, &r, 1, &v);
            } else if (kind[0] == 'i') {
                fmi2Integer v = atoi(text);
                st = f[k].setInteger(f[k].c, &r, 1, &v);
            } else {
                fmi2String v = text;
                st = f[k].setString(f[k].c, &r, 1, &v);
            }
            if (!check(k, "fmi2Set", st)) return 1;
        } else if (strcmp(kind, "link") == 0) {
            if (nl == MAXL || fscanf(plan, "%d %d %d %d", &link[nl][0], &link[nl][1], &link[nl][2], &link[nl][3]) != 4)
                return 2;
            nl++;
        } else if (strcmp(kind, "print") == 0) {
            if (np == MAXL || fscanf(plan, "%d %d", &printed[np][0], &printed[np][1]) != 2) return 2;
            np++;
        } else {
            fprintf(stderr, "unknown plan item %s\n", kind);
            return 2;
        }
    }
    fclose(plan);
    for (int k = 0; k < nf; k++)
        if (!check(k, "fmi2EnterInitializationMode", f[k].enter(f[k].c))) return 1;
    int ok = 1;
    for (int k = 0; ok && k < nf; k++) {
        for (int l = 0; ok && l < nl; l++)
            if (link[l][2] == k) {
                fmi2ValueReference src = (fmi2ValueReference)link[l][1], dst = (fmi2ValueReference)link[l][3];
                fmi2Real v;
                ok = check(link[l][0], "fmi2GetReal", f[link[l][0]].getReal(f[link[l][0]].c, &src, 1, &v)) &&
                     check(k, "fmi2SetReal", f[k].setReal(f[k].c, &dst, 1, &v));
            }
        ok = ok && check(k, "fmi2ExitInitializationMode", f[k].exit_(f[k].c));
    }
    long done = 0;
    for (long n = 0; ok && n < steps; n++, done++)
        for (int k = 0; ok && k < nf; k++) {
            for (int l = 0; ok && l < nl; l++)
                if (link[l][2] == k) {
                    fmi2ValueReference src = (fmi2ValueReference)link[l][1], dst = (fmi2ValueReference)link[l][3];
                    fmi2Real v;
                    ok = check(link[l][0], "fmi2GetReal", f[link[l][0]].getReal(f[link[l][0]].c, &src, 1, &v)) &&
                         check(k, "fmi2SetReal", f[k].setReal(f[k].c, &dst, 1, &v));
                }
            ok = ok && check(k, "fmi2DoStep", f[k].step(f[k].c, n * h, h, fmi2True));
        }
    for (int p = 0; ok && p < np; p++) {
        fmi2ValueReference vr = (fmi2ValueReference)printed[p][1];
        fmi2Real v;
        ok = check(printed[p][0], "fmi2GetReal", f[printed[p][0]].getReal(f[printed[p][0]].c, &vr, 1, &v));
        if (ok) printf("VALUE %d %d %.17g\n", printed[p][0], printed[p][1], v);
    }
    for (int k = 0; k < nf; k++) {
        if (ok) check(k, "fmi2Terminate", f[k].terminate(f[k].c));
        f[k].free_(f[k].c);
    }
    printf("DONE %ld\n", done);
    return ok ? 0 : 1;
}
