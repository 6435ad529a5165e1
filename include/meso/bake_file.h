/* The bake file container (docs/bake-format.md) and the bake cache.
 *
 * A bake file holds a kind ("vdm", ...), the kind's layout version, the hash of the source it
 * was baked from, the parameters as JSON text, and up to MESO_BAKE_MAX_ARRAYS named arrays
 * (type + shape + data), closed by an FNV-1a 64 checksum. Little-endian.
 *
 * Usage
 *   meso_bake_file bake = {.kind = "vdm", .kind_version = 1, .source_hash = h,
 *                          .params_json = "{\"width\": 128}", .num_arrays = 1};
 *   bake.arrays[0] = (meso_bake_array){.name = "weights", .type = MESO_BAKE_F32,
 *                                      .num_dims = 2, .dims = {128, 8}, .data = w};
 *   meso_bake_file_save(ctx, &bake, "w.mesobake");
 *   meso_bake_file *loaded = NULL;
 *   if (meso_bake_file_load(ctx, "w.mesobake", &loaded) == MESO_OK) {
 *       const meso_bake_array *a = meso_bake_file_find(loaded, "weights");
 *       ...
 *       meso_bake_file_destroy(loaded);
 *   }
 *
 * Ownership: a loaded bake owns its arrays and params (one buffer, freed by destroy); a bake
 * you fill in for saving only borrows them.
 * Threads: every function is thread-safe on different bake files; a loaded bake may be read
 * from many threads.
 */
#ifndef MESO_BAKE_FILE_H
#define MESO_BAKE_FILE_H

#include "meso/core.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_BAKE_MAX_ARRAYS 16
#define MESO_BAKE_MAX_DIMS 6
#define MESO_BAKE_MAX_FILE_BYTES (UINT64_C(4) << 30)
#define MESO_BAKE_MAX_PARAMS_BYTES 65536u
#define MESO_BAKE_FORMAT_VERSION 1u

typedef enum meso_bake_type {
    MESO_BAKE_F32 = 1,
    MESO_BAKE_U8 = 2,
    MESO_BAKE_U16 = 3,
    MESO_BAKE_I32 = 4,
    MESO_BAKE_F16 = 5, /* IEEE 754 binary16 */
} meso_bake_type;

typedef struct meso_bake_array {
    char name[32];
    meso_bake_type type;
    int num_dims;
    uint64_t dims[MESO_BAKE_MAX_DIMS];
    void *data; /* owned by the bake file when loaded; borrowed when saving */
} meso_bake_array;

typedef struct meso_bake_file {
    char kind[32]; /* "vdm", "horizon", ... */
    uint32_t kind_version;
    uint64_t source_hash;
    char *params_json; /* owned when loaded; borrowed when saving */
    int num_arrays;
    meso_bake_array arrays[MESO_BAKE_MAX_ARRAYS];
} meso_bake_file;

/* Write atomically (temporary file + rename). Validates names, kind, types, dims (each >= 1)
 * and that every array has data: MESO_ERROR_INVALID_ARGUMENT naming the array; MESO_ERROR_IO
 * naming the file. */
meso_result meso_bake_file_save(meso_context *ctx, const meso_bake_file *bake, const char *path);
/* Read and validate (magic, version, sizes against the file length, checksum); a truncated or
 * corrupted file is MESO_ERROR_FORMAT naming the file and what is wrong. */
meso_result meso_bake_file_load(meso_context *ctx, const char *path, meso_bake_file **out_bake);
void meso_bake_file_destroy(meso_bake_file *bake);
/* The array named `name`, NULL when absent. */
const meso_bake_array *meso_bake_file_find(const meso_bake_file *bake, const char *name);
/* Bytes of one element of `type` (0 for an unknown type). */
size_t meso_bake_type_size(meso_bake_type type);
/* Elements in the array (product of its dims). */
uint64_t meso_bake_array_count(const meso_bake_array *array);
/* Check that every element of an f32 or f16 array is finite and within [min, max]: a file
 * whose checksum is valid may still hold Inf or NaN (written so, or crafted), which a
 * technique would turn into out-of-range indices. Kinds' loaders call it for every array they
 * read. MESO_OK, or MESO_ERROR_FORMAT logged as `<name>: array "weights": element 17 is inf,
 * not a finite number in [-65504, 65504]`; MESO_ERROR_INVALID_ARGUMENT for another type.
 * Thread-safe. */
meso_result meso_bake_array_check_values(meso_context *ctx, const char *name,
                                         const meso_bake_array *array, double min, double max);

#ifdef __cplusplus
}
#endif
#endif
