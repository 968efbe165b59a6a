/* libFuzzer harness of the vehicle's legs (sarins_fmu/core/vehicle.c: sarins_vehicle_parse_legs, then
 * sarins_vehicle_segments and up to 4000 steps of the stream): what the VehicleMotion FMU runs on its
 * `legs` String parameter, on arbitrary bytes (cut at 4095 bytes and a NUL, as the glue's string buffer).
 * The first byte, when present, picks the grid (1, 0.5, 0.01 or 7 s) and the start latitude.  Findings:
 * any sanitizer report, or an accepted drive whose published outputs are not finite while the stream
 * says it is valid (abort()).
 *
 * Build and run with libFuzzer (clang), from the repository root:
 *   clang -std=c11 -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -Isarins_fmu/core \
 *       tests/fuzz/fuzz_vehicle_legs.c sarins_fmu/core/vehicle.c sarins_fmu/core/schedule.c \
 *       sarins_fmu/core/ambient.c sarins_fmu/core/earth.c sarins_fmu/core/rng.c sarins_fmu/core/report.c \
 *       sarins_fmu/core/smath.c -o /tmp/fuzz_vehicle_legs
 *   /tmp/fuzz_vehicle_legs -max_len=4200 -max_total_time=60
 * Without libFuzzer (any C11 compiler, e.g. gcc -fsanitize=address,undefined), add -DSARINS_FUZZ_MAIN: the
 * program then runs the harness once on each line of the files named on its command line.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "smath.h"
#include "vehicle.h"

#define MAX_LEGS 2048 /* as fmus/c/vehicle_motion/model.c: SARINS_STRING_MAX / 2 */
#define MAX_RUN 4000

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const double grids[4] = {1.0, 0.5, 0.01, 7.0};
    char text[4096];
    sarins_vehicle_params p;
    sarins_vehicle_params_default(&p);
    if (size > 0) {
        p.step = grids[data[0] & 3];
        p.lat0 = ((double)(data[0] >> 2) - 32.0) * 0.0487; /* -1.56 .. 1.51 rad: some beyond 89.9 deg */
        p.seed = data[0];
        data++;
        size--;
    }
    size_t n = size < sizeof text - 1 ? size : sizeof text - 1;
    memcpy(text, data, n);
    text[n] = '\0';
    sarins_leg legs[MAX_LEGS];
    char msg[512];
    int64_t n_legs = sarins_vehicle_parse_legs(text, legs, MAX_LEGS, msg, sizeof msg);
    if (n_legs < 0)
        return 0;
    static sarins_vehicle_segment segs[3 * MAX_LEGS + 2];
    int64_t n_segs = 0, n_steps = 0;
    if (sarins_vehicle_segments(&p, legs, n_legs, segs, 3 * MAX_LEGS + 2, &n_segs, &n_steps, msg, sizeof msg))
        return 0;
    if (n_segs < 1 || n_steps < 1)
        abort(); /* an accepted drive has a last step */
    sarins_vehicle v;
    sarins_vehicle_start(&v, &p);
    double out[SARINS_VEH_N_OUT];
    for (int64_t k = 0; k < MAX_RUN && k <= n_steps + 2; k++) {
        if (!sarins_vehicle_valid(&v, msg, sizeof msg))
            return 0; /* refused at this step, as the FMU does */
        sarins_vehicle_step(&v, segs, n_segs, out);
        for (int j = 0; j < SARINS_VEH_N_OUT; j++)
            if (!isfinite(out[j]))
                abort(); /* a valid state published garbage */
    }
    return 0;
}

#ifdef SARINS_FUZZ_MAIN
int main(int argc, char **argv)
{
    char line[1024];
    long runs = 0;
    for (int k = 1; k < argc; k++) {
        FILE *f = fopen(argv[k], "rb");
        if (f == NULL) {
            fprintf(stderr, "cannot open %s\n", argv[k]);
            return 2;
        }
        while (fgets(line, sizeof line, f) != NULL) {
            size_t n = strcspn(line, "\n");
            LLVMFuzzerTestOneInput((const uint8_t *)line, n);
            runs++;
        }
        fclose(f);
    }
    printf("fuzz harness: %ld inputs\n", runs);
    return 0;
}
#endif
