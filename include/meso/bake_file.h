/* The bake file container (docs/bake-format.md). */
#ifndef MESO_BAKE_FILE_H
#define MESO_BAKE_FILE_H

#include "meso/core.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_BAKE_MAX_ARRAYS 16
#define MESO_BAKE_MAX_DIMS 6
#define MESO_BAKE_MAX_FILE_BYTES (UINT64_C(4) << 30)

typedef enum meso_bake_type {
    MESO_BAKE_F32 = 1,
    MESO_BAKE_U8 = 2,
    MESO_BAKE_U16 = 3,
    MESO_BAKE_I32 = 4,
} meso_bake_type;

typedef struct meso_bake_array {
    char name[32];
    meso_bake_type type;
    int num_dims;
    uint64_t dims[MESO_BAKE_MAX_DIMS];
    void *data; /* owned by the bake file when loaded; borrowed when saving */
} meso_bake_array;

typedef struct meso_bake_file {
    char kind[32];        /* "vdm", "horizon", ... */
    uint32_t kind_version;
    uint64_t source_hash;
    char *params_json;    /* owned when loaded; borrowed when saving */
    int num_arrays;
    meso_bake_array arrays[MESO_BAKE_MAX_ARRAYS];
} meso_bake_file;

/* Write atomically. */
meso_result meso_bake_file_save(meso_context *ctx, const meso_bake_file *bake, const char *path);
/* Read and validate (magic, version, sizes against the file length, checksum); a truncated or
 * corrupted file is MESO_ERROR_FORMAT naming the file and what is wrong. */
meso_result meso_bake_file_load(meso_context *ctx, const char *path, meso_bake_file **out_bake);
void meso_bake_file_destroy(meso_bake_file *bake);
/* The array named `name`, NULL when absent. */
const meso_bake_array *meso_bake_file_find(const meso_bake_file *bake, const char *name);

#ifdef __cplusplus
}
#endif
#endif
