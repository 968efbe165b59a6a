/* FMU-state pointer safety of the native glue, linked with an FMU's sources (no dlopen), meant to be built
 * with -fsanitize=address,undefined: a freed state, another instance's state and a made-up pointer passed
 * to Set / Free / SerializedSize / Serialize must each return an error status without reading through the
 * pointer (AddressSanitizer reports a use-after-free otherwise); a state saved and never freed is freed
 * with the instance (LeakSanitizer).  Build with -DFMI3 for the FMI 3.0 glue.
 *
 * usage: state_pointers TOKEN      prints "CASE <name> <status>" per case, then "DONE"; exit 0
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef FMI3
#include "fmi3Functions.h"
typedef fmi3Instance inst;
typedef fmi3FMUState fstate;
static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    (void)env; (void)category;
    printf("LOG %d %s\n", (int)status, message);
}
static inst make(const char *token, const char *name)
{
    inst c = fmi3InstantiateCoSimulation(name, token, NULL, fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0,
                                         NULL, logger, NULL);
    if (c == NULL || fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK
        || fmi3ExitInitializationMode(c) != fmi3OK)
        exit(2);
    return c;
}
static void restart(inst c)
{
    if (fmi3Reset(c) != fmi3OK || fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK
        || fmi3ExitInitializationMode(c) != fmi3OK)
        exit(2);
}
#define GET(c, s) fmi3GetFMUState((c), (s))
#define SET(c, s) fmi3SetFMUState((c), (s))
#define FREE(c, s) fmi3FreeFMUState((c), (s))
#define SIZE(c, s, n) fmi3SerializedFMUStateSize((c), (s), (n))
#define SER(c, s, b, n) fmi3SerializeFMUState((c), (s), (b), (n))
#define FREE_INSTANCE(c) fmi3FreeInstance(c)
#else
#include "fmi2Functions.h"
typedef fmi2Component inst;
typedef fmi2FMUstate fstate;
static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...)
{
    (void)env; (void)name; (void)category;
    va_list ap;
    va_start(ap, message);
    printf("LOG %d ", (int)status);
    vprintf(message, ap);
    printf("\n");
    va_end(ap);
}
static const fmi2CallbackFunctions CALLBACKS = {logger, calloc, free, NULL, NULL};
static inst make(const char *token, const char *name)
{
    inst c = fmi2Instantiate(name, fmi2CoSimulation, token, NULL, &CALLBACKS, fmi2False, fmi2False);
    if (c == NULL || fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK
        || fmi2EnterInitializationMode(c) != fmi2OK || fmi2ExitInitializationMode(c) != fmi2OK)
        exit(2);
    return c;
}
static void restart(inst c)
{
    if (fmi2Reset(c) != fmi2OK || fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK
        || fmi2EnterInitializationMode(c) != fmi2OK || fmi2ExitInitializationMode(c) != fmi2OK)
        exit(2);
}
#define GET(c, s) fmi2GetFMUstate((c), (s))
#define SET(c, s) fmi2SetFMUstate((c), (s))
#define FREE(c, s) fmi2FreeFMUstate((c), (s))
#define SIZE(c, s, n) fmi2SerializedFMUstateSize((c), (s), (n))
#define SER(c, s, b, n) fmi2SerializeFMUstate((c), (s), (fmi2Byte *)(b), (n))
#define FREE_INSTANCE(c) fmi2FreeInstance(c)
#endif

#define CASE(name, call)                                                                                    \
    do {                                                                                                     \
        restart(a);                                                                                          \
        printf("CASE %s %d\n", (name), (int)(call));                                                         \
    } while (0)

int main(int argc, char **argv)
{
    if (argc != 2)
        return 2;
    inst a = make(argv[1], "a"), b = make(argv[1], "b");
    fstate freed = NULL, foreign = NULL, kept = NULL, leaked = NULL;
    if (GET(a, &freed) != 0 || GET(b, &foreign) != 0 || GET(a, &kept) != 0 || GET(a, &leaked) != 0)
        return 2;
    fstate stale = freed;
    if (FREE(a, &freed) != 0 || freed != NULL)
        return 2;
    static unsigned char buffer[1 << 20];
    size_t n = 0;
    double junk[64] = {0};
    fstate made_up = (fstate)junk;
    CASE("set_freed", SET(a, stale));
    CASE("free_freed", FREE(a, &stale));
    CASE("size_freed", SIZE(a, stale, &n));
    CASE("serialize_freed", SER(a, stale, buffer, sizeof buffer));
    CASE("set_foreign", SET(a, foreign));
    CASE("free_foreign", FREE(a, &foreign));
    CASE("serialize_foreign", SER(a, foreign, buffer, sizeof buffer));
    CASE("set_made_up", SET(a, made_up));
    CASE("free_made_up", FREE(a, &made_up));
    CASE("get_into_freed", GET(a, &stale));
    CASE("set_kept", SET(a, kept));
    CASE("free_kept", FREE(a, &kept));
    if (FREE(b, &foreign) != 0)
        return 2;
    FREE_INSTANCE(a); /* `leaked` is freed with its instance */
    FREE_INSTANCE(b);
    printf("DONE\n");
    return 0;
}
