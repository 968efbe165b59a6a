/* Interface between the FMI 3.0 test-fixture glue (glue3.c) and one fixture model.
 *
 * A model is a struct of plain values; its variables are described by a table of
 * VarInfo (value reference, type, role, byte offset in the struct, dimension), so the
 * glue moves values with memcpy and checks value references, types, counts and the
 * state in which a variable may be set.  Arrays have a fixed length or the length of
 * the model's structural parameter (model_dim), at most FIXTURE_DIM_MAX elements,
 * stored inside the struct: nothing is allocated after instantiation.
 */
#ifndef FIXTURE3_H
#define FIXTURE3_H

#include <stddef.h>
#include "fmi3Functions.h"

#define FIXTURE_DIM_MAX 64
#define FIXTURE_STRING_MAX 64 /* bytes of a String variable's buffer, terminating zero included */
#define DIM_STRUCTURAL (-1) /* VarInfo.dim: the array has model_dim() elements */

typedef enum { T_FLOAT32, T_FLOAT64, T_INT32, T_UINT64, T_BOOLEAN, T_STRING } VarType; /* T_STRING: char[FIXTURE_STRING_MAX] */
typedef enum { R_STRUCTURAL, R_PARAMETER, R_INPUT, R_OUTPUT } VarRole;

typedef struct {
    fmi3ValueReference vr;
    VarType type;
    VarRole role;
    size_t offset; /* offsetof(model struct, field) */
    int dim;       /* 0: scalar; > 0: fixed length; DIM_STRUCTURAL */
    int columns;   /* 0: one dimension; > 0: a second, fixed dimension (row-major [dim][columns]) */
} VarInfo;

/* provided by each model */
extern const char *const MODEL_TOKEN;       /* instantiationToken of its model description */
extern const VarInfo MODEL_VARIABLES[];
extern const size_t MODEL_VARIABLE_COUNT;
size_t model_size(void);
void model_defaults(void *model);
size_t model_dim(const void *model);          /* the structural dimension */
const char *model_check(const void *model);   /* NULL, or why the parameters are invalid */
void model_start(void *model, double time);   /* outputs at the start time */
int model_step(void *model, double time, double step); /* nonzero: the model asks to end the run */

#endif
