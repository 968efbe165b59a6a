/* What the FMI 2.0 and FMI 3.0 C test hosts (native_fmu_host.c, native_fmu3_host.c) share: loading a
 * binary and its symbols on Linux (dlopen) and Windows (LoadLibrary), the value-reference lists of the
 * command line, the rows file of inputs and the bit-pattern output lines.  Header-only (static
 * functions), so each host stays one translation unit. */
#ifndef SARINS_HOST_COMMON_H
#define SARINS_HOST_COMMON_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#include <windows.h>
typedef HMODULE lib_t;
static lib_t lib_open(const char *path) { return LoadLibraryA(path); }
static void *lib_sym(lib_t lib, const char *name) { return (void *)(uintptr_t)GetProcAddress(lib, name); }
#else
#include <dlfcn.h>
typedef void *lib_t;
static lib_t lib_open(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *lib_sym(lib_t lib, const char *name) { return dlsym(lib, name); }
#endif

/* One function pointer to resolve: where it goes and the exported name. */
typedef struct {
    void **slot;
    const char *name;
} host_symbol;

/* Every symbol of syms[0..n) into its slot; 0 (and the missing name on stderr) when one is absent. */
static int host_resolve(lib_t lib, const host_symbol *syms, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        void *p = lib_sym(lib, syms[i].name);
        if (p == NULL) {
            fprintf(stderr, "missing symbol %s\n", syms[i].name);
            return 0;
        }
        memcpy(syms[i].slot, &p, sizeof p);
    }
    return 1;
}

/* The comma-separated value references of text appended to vr[*n..max); stops at the first other character. */
static void host_parse_vrs(const char *text, uint32_t *vr, size_t *n, size_t max)
{
    for (char *p = (char *)text; *p && *n < max;) {
        vr[(*n)++] = (uint32_t)strtoul(p, &p, 10);
        if (*p == ',')
            p++;
        else if (*p)
            break;
    }
}

/* The float64 values of the file at path (native byte order) into a new array *values of *count values;
 * 0 when the file is missing, empty or unreadable. */
static int host_read_doubles(const char *path, double **values, long *count)
{
    FILE *in = fopen(path, "rb");
    long bytes = -1;
    if (in && fseek(in, 0, SEEK_END) == 0)
        bytes = ftell(in);
    *values = (bytes > 0 && fseek(in, 0, SEEK_SET) == 0) ? malloc((size_t)bytes) : NULL;
    int ok = *values != NULL && fread(*values, 1, (size_t)bytes, in) == (size_t)bytes;
    if (in)
        fclose(in);
    *count = ok ? bytes / (long)sizeof(double) : 0;
    return ok;
}

/* "TAG k <16 hex digits per value>": the values' bit patterns, so that outputs compare bit for bit. */
static void host_print_bits(const char *tag, long k, const double *v, size_t n)
{
    printf("%s %ld", tag, k);
    for (size_t i = 0; i < n; i++) {
        uint64_t bits;
        memcpy(&bits, &v[i], 8);
        printf(" %016llx", (unsigned long long)bits);
    }
    printf("\n");
}

#endif
