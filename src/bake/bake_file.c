/* The bake file container (docs/bake-format.md): writing, reading, validation. */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "bake_internal.h"
#include "meso/runtime.h"
#include "meso/math.h"

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "meso bake files store arrays in host order, which must be little-endian"
#endif

#define HEADER_BYTES 72u /* fixed header up to the parameter text */
#define ENTRY_BYTES 104u /* one array table entry */
#define CHECKSUM_BYTES 8u
#define NAME_BYTES 32u

/* A loaded bake: the public struct plus the one buffer its arrays and params point into. */
typedef struct loaded_bake {
    meso_bake_file bake;
    char *buffer;
} loaded_bake;

size_t meso_bake_type_size(meso_bake_type type) {
    switch (type) {
    case MESO_BAKE_F32:
        return 4;
    case MESO_BAKE_U8:
        return 1;
    case MESO_BAKE_U16:
        return 2;
    case MESO_BAKE_I32:
        return 4;
    case MESO_BAKE_F16:
        return 2;
    }
    return 0;
}

uint64_t meso_bake_array_count(const meso_bake_array *array) {
    uint64_t count = 1;
    for (int i = 0; i < array->num_dims && i < MESO_BAKE_MAX_DIMS; i++) count *= array->dims[i];
    return count;
}

static uint64_t align8(uint64_t x) { return (x + 7u) & ~UINT64_C(7); }

static void put_u32(unsigned char *p, uint32_t v) {
    for (int i = 0; i < 4; i++) p[i] = (unsigned char)(v >> (8 * i));
}
static void put_u64(unsigned char *p, uint64_t v) {
    for (int i = 0; i < 8; i++) p[i] = (unsigned char)(v >> (8 * i));
}
static uint32_t get_u32(const unsigned char *p) {
    uint32_t v = 0;
    for (int i = 0; i < 4; i++) v |= (uint32_t)p[i] << (8 * i);
    return v;
}
static uint64_t get_u64(const unsigned char *p) {
    uint64_t v = 0;
    for (int i = 0; i < 8; i++) v |= (uint64_t)p[i] << (8 * i);
    return v;
}

/* Names and kinds: 1-31 characters of [a-z0-9_], NUL-terminated within 32 bytes. */
static bool valid_name(const char *name, size_t capacity) {
    size_t n = 0;
    while (n < capacity && name[n]) {
        char c = name[n];
        if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) return false;
        n++;
    }
    return n >= 1 && n < capacity;
}

/* Bytes of an array's data, or 0 when its dims or type are invalid or the size overflows. */
static uint64_t array_bytes(meso_bake_type type, int num_dims, const uint64_t *dims) {
    uint64_t bytes = meso_bake_type_size(type);
    if (bytes == 0 || num_dims < 1 || num_dims > MESO_BAKE_MAX_DIMS) return 0;
    for (int i = 0; i < num_dims; i++) {
        if (dims[i] == 0 || dims[i] > MESO_BAKE_MAX_FILE_BYTES) return 0;
        if (bytes > MESO_BAKE_MAX_FILE_BYTES / dims[i]) return 0; /* no overflow, no absurd size */
        bytes *= dims[i];
    }
    return bytes;
}

/* ---- Writing ------------------------------------------------------------------------------ */

static bool write_hashed(FILE *f, const void *data, size_t size, uint64_t *hash) {
    *hash = meso_hash64(data, size, *hash);
    return fwrite(data, 1, size, f) == size;
}

meso_result meso_bake_file_save(meso_context *ctx, const meso_bake_file *bake, const char *path) {
    if (!bake || !path)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "bake file: NULL argument");
    if (!valid_name(bake->kind, sizeof(bake->kind)))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: kind: must be 1-31 characters of [a-z0-9_]", path);
    if (bake->num_arrays < 0 || bake->num_arrays > MESO_BAKE_MAX_ARRAYS)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: num_arrays %d is outside 0-%d",
                              path, bake->num_arrays, MESO_BAKE_MAX_ARRAYS);
    size_t params_size = bake->params_json ? strlen(bake->params_json) : 0;
    if (params_size > MESO_BAKE_MAX_PARAMS_BYTES)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: params: %zu bytes exceed the limit %u", path, params_size,
                              MESO_BAKE_MAX_PARAMS_BYTES);

    /* Layout: header, params, padding, table, arrays (8-aligned), checksum. */
    uint64_t table_offset = align8(HEADER_BYTES + params_size);
    uint64_t offset = table_offset + (uint64_t)bake->num_arrays * ENTRY_BYTES;
    uint64_t offsets[MESO_BAKE_MAX_ARRAYS], sizes[MESO_BAKE_MAX_ARRAYS];
    for (int a = 0; a < bake->num_arrays; a++) {
        const meso_bake_array *array = &bake->arrays[a];
        if (!valid_name(array->name, sizeof(array->name)))
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                                  "%s: arrays[%d].name: must be 1-31 characters of [a-z0-9_]", path,
                                  a);
        for (int b = 0; b < a; b++)
            if (strcmp(bake->arrays[b].name, array->name) == 0)
                return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                                      "%s: array \"%s\": name used twice", path, array->name);
        uint64_t bytes = array_bytes(array->type, array->num_dims, array->dims);
        if (bytes == 0)
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                                  "%s: array \"%s\": invalid type, dims or size", path,
                                  array->name);
        if (!array->data)
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: array \"%s\": no data",
                                  path, array->name);
        offsets[a] = align8(offset);
        sizes[a] = bytes;
        offset = offsets[a] + bytes;
    }
    uint64_t checksum_offset = align8(offset);
    uint64_t file_size = checksum_offset + CHECKSUM_BYTES;
    if (file_size > MESO_BAKE_MAX_FILE_BYTES)
        return meso_log_error(
            ctx, MESO_ERROR_LIMIT, "%s: %llu bytes exceed the bake file limit %llu", path,
            (unsigned long long)file_size, (unsigned long long)MESO_BAKE_MAX_FILE_BYTES);

    meso_atomic_file file;
    meso_result result = meso_atomic_file_open(ctx, path, &file);
    if (result != MESO_OK) return result;

    uint64_t hash = MESO_HASH_SEED;
    static const unsigned char zeros[8] = {0};
    unsigned char header[HEADER_BYTES] = {0};
    memcpy(header, "MESOBAKE", 8);
    put_u32(header + 8, MESO_BAKE_FORMAT_VERSION);
    put_u32(header + 12, bake->kind_version);
    memcpy(header + 16, bake->kind, strlen(bake->kind));
    put_u64(header + 48, bake->source_hash);
    put_u64(header + 56, file_size);
    put_u32(header + 64, (uint32_t)bake->num_arrays);
    put_u32(header + 68, (uint32_t)params_size);
    errno = 0;
    bool ok = write_hashed(file.file, header, sizeof(header), &hash);
    if (params_size) ok = ok && write_hashed(file.file, bake->params_json, params_size, &hash);
    ok = ok && write_hashed(file.file, zeros, table_offset - (HEADER_BYTES + params_size), &hash);
    for (int a = 0; a < bake->num_arrays && ok; a++) {
        const meso_bake_array *array = &bake->arrays[a];
        unsigned char entry[ENTRY_BYTES] = {0};
        memcpy(entry, array->name, strlen(array->name));
        put_u32(entry + 32, (uint32_t)array->type);
        put_u32(entry + 36, (uint32_t)array->num_dims);
        for (int d = 0; d < array->num_dims; d++) put_u64(entry + 40 + 8 * d, array->dims[d]);
        put_u64(entry + 88, offsets[a]);
        put_u64(entry + 96, sizes[a]);
        ok = write_hashed(file.file, entry, sizeof(entry), &hash);
    }
    uint64_t position = table_offset + (uint64_t)bake->num_arrays * ENTRY_BYTES;
    for (int a = 0; a < bake->num_arrays && ok; a++) {
        ok = write_hashed(file.file, zeros, offsets[a] - position, &hash);
        ok = ok && write_hashed(file.file, bake->arrays[a].data, sizes[a], &hash);
        position = offsets[a] + sizes[a];
    }
    ok = ok && write_hashed(file.file, zeros, checksum_offset - position, &hash);
    unsigned char checksum[CHECKSUM_BYTES];
    put_u64(checksum, hash);
    ok = ok && fwrite(checksum, 1, sizeof(checksum), file.file) == sizeof(checksum);
    if (!ok) {
        int reason = errno ? errno : EIO;
        meso_atomic_file_abort(&file);
        return meso_log_error(ctx, MESO_ERROR_WRITE, "%s: cannot write: %s", path,
                              strerror(reason));
    }
    return meso_atomic_file_commit(ctx, &file);
}

/* ---- Reading ------------------------------------------------------------------------------ */

static meso_result parse(meso_context *ctx, const char *path, char *buffer, size_t size,
                         loaded_bake *out) {
    const unsigned char *bytes = (const unsigned char *)buffer;
    meso_bake_file *bake = &out->bake;
    if (size < HEADER_BYTES + CHECKSUM_BYTES)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: truncated: %zu bytes, shorter than a bake file header", path,
                              size);
    if (memcmp(bytes, "MESOBAKE", 8) != 0)
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: not a meso bake file (bad magic)", path);
    uint32_t version = get_u32(bytes + 8);
    if (version != MESO_BAKE_FORMAT_VERSION)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: format version %u is not supported (this meso reads %u)", path,
                              version, MESO_BAKE_FORMAT_VERSION);
    memcpy(bake->kind, bytes + 16, NAME_BYTES);
    if (!valid_name(bake->kind, NAME_BYTES))
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: kind: invalid characters", path);
    uint64_t file_size = get_u64(bytes + 56);
    if (file_size > size)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: truncated: %zu bytes, the header says %llu", path, size,
                              (unsigned long long)file_size);
    if (file_size < size)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: %zu trailing bytes after the declared end %llu", path,
                              size - (size_t)file_size, (unsigned long long)file_size);
    uint32_t num_arrays = get_u32(bytes + 64), params_size = get_u32(bytes + 68);
    if (num_arrays > MESO_BAKE_MAX_ARRAYS)
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: %u arrays exceed the limit %d", path,
                              num_arrays, MESO_BAKE_MAX_ARRAYS);
    if (params_size > MESO_BAKE_MAX_PARAMS_BYTES)
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: params: %u bytes exceed the limit %u",
                              path, params_size, MESO_BAKE_MAX_PARAMS_BYTES);
    uint64_t table_offset = align8(HEADER_BYTES + (uint64_t)params_size);
    uint64_t payload_start = table_offset + (uint64_t)num_arrays * ENTRY_BYTES;
    uint64_t payload_end = size - CHECKSUM_BYTES;
    if (payload_start > payload_end)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: truncated: the array table ends at %llu, past the data end %llu",
                              path, (unsigned long long)payload_start,
                              (unsigned long long)payload_end);
    uint64_t checksum = meso_hash64(bytes, (size_t)payload_end, MESO_HASH_SEED);
    if (checksum != get_u64(bytes + payload_end))
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: checksum mismatch (file corrupted)",
                              path);

    bake->kind_version = get_u32(bytes + 12);
    bake->source_hash = get_u64(bytes + 48);
    /* The params text is NUL-terminated in place: its padding byte (or the table's first byte,
     * already parsed below into locals) is overwritten only after the table is read. */
    bake->num_arrays = (int)num_arrays;
    for (uint32_t a = 0; a < num_arrays; a++) {
        const unsigned char *entry = bytes + table_offset + (uint64_t)a * ENTRY_BYTES;
        meso_bake_array *array = &bake->arrays[a];
        memcpy(array->name, entry, NAME_BYTES);
        if (!valid_name(array->name, NAME_BYTES))
            return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: arrays[%u]: invalid name", path, a);
        for (uint32_t b = 0; b < a; b++)
            if (strcmp(bake->arrays[b].name, array->name) == 0)
                return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: array \"%s\": name used twice",
                                      path, array->name);
        uint32_t type = get_u32(entry + 32), num_dims = get_u32(entry + 36);
        if (meso_bake_type_size((meso_bake_type)type) == 0)
            return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: array \"%s\": unknown type %u", path,
                                  array->name, type);
        if (num_dims < 1 || num_dims > MESO_BAKE_MAX_DIMS)
            return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                  "%s: array \"%s\": %u dimensions (1-%d allowed)", path,
                                  array->name, num_dims, MESO_BAKE_MAX_DIMS);
        array->type = (meso_bake_type)type;
        array->num_dims = (int)num_dims;
        for (int d = 0; d < MESO_BAKE_MAX_DIMS; d++)
            array->dims[d] = (uint32_t)d < num_dims ? get_u64(entry + 40 + 8 * d) : 0;
        uint64_t offset = get_u64(entry + 88), stored = get_u64(entry + 96);
        uint64_t bytes_needed = array_bytes(array->type, array->num_dims, array->dims);
        if (bytes_needed == 0)
            return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                  "%s: array \"%s\": dims are zero or their product is absurd",
                                  path, array->name);
        if (bytes_needed != stored)
            return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                  "%s: array \"%s\": size %llu does not match its dims (%llu)",
                                  path, array->name, (unsigned long long)stored,
                                  (unsigned long long)bytes_needed);
        if (offset % 8 != 0 || offset < payload_start || offset > payload_end ||
            stored > payload_end - offset)
            return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                  "%s: array \"%s\": offset %llu + size %llu is outside the "
                                  "payload %llu-%llu",
                                  path, array->name, (unsigned long long)offset,
                                  (unsigned long long)stored, (unsigned long long)payload_start,
                                  (unsigned long long)payload_end);
        for (uint32_t b = 0; b < a; b++) {
            const unsigned char *other = bytes + table_offset + (uint64_t)b * ENTRY_BYTES;
            uint64_t o = get_u64(other + 88), s = get_u64(other + 96);
            if (offset < o + s && o < offset + stored)
                return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                      "%s: array \"%s\" overlaps array \"%s\"", path, array->name,
                                      bake->arrays[b].name);
        }
        array->data = buffer + offset;
    }
    /* NUL-terminate the params text: the byte after it is padding or the table's first byte,
     * whose name was copied out above; an empty text becomes "". */
    memmove(buffer, buffer + HEADER_BYTES, params_size);
    buffer[params_size] = 0;
    bake->params_json = buffer;
    return MESO_OK;
}

meso_result meso_bake_file_load(meso_context *ctx, const char *path, meso_bake_file **out_bake) {
    if (out_bake) *out_bake = NULL;
    if (!path || !out_bake)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "bake file: NULL argument");
    char *buffer = NULL;
    size_t size = 0;
    loaded_bake *loaded = NULL;
    meso_result result =
        meso_file_read(ctx, path, (size_t)MESO_BAKE_MAX_FILE_BYTES, &buffer, &size);
    if (result != MESO_OK) goto fail;
    loaded = calloc(1, sizeof(*loaded));
    if (!loaded) {
        result = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
        goto fail;
    }
    result = parse(ctx, path, buffer, size, loaded);
    if (result != MESO_OK) goto fail;
    loaded->buffer = buffer;
    *out_bake = &loaded->bake;
    return MESO_OK;
fail:
    free(loaded);
    free(buffer);
    return result;
}

void meso_bake_file_destroy(meso_bake_file *bake) {
    if (!bake) return;
    loaded_bake *loaded = (loaded_bake *)bake; /* bake is the first member */
    free(loaded->buffer);
    free(loaded);
}

const meso_bake_array *meso_bake_file_find(const meso_bake_file *bake, const char *name) {
    if (!bake || !name) return NULL;
    for (int a = 0; a < bake->num_arrays && a < MESO_BAKE_MAX_ARRAYS; a++)
        if (strncmp(bake->arrays[a].name, name, sizeof(bake->arrays[a].name)) == 0)
            return &bake->arrays[a];
    return NULL;
}

meso_result meso_bake_array_check_values(meso_context *ctx, const char *name,
                                         const meso_bake_array *array, double min, double max) {
    if (!array || (array->type != MESO_BAKE_F32 && array->type != MESO_BAKE_F16))
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: array \"%s\": not a float array", name,
                              array ? array->name : "");
    uint64_t count = meso_bake_array_count(array);
    for (uint64_t i = 0; i < count; i++) {
        double value;
        if (array->type == MESO_BAKE_F32) {
            float f;
            memcpy(&f, (const unsigned char *)array->data + 4 * i, sizeof(f));
            value = f;
        } else {
            uint16_t h;
            memcpy(&h, (const unsigned char *)array->data + 2 * i, sizeof(h));
            value = meso_half_to_float(h);
        }
        /* written so that NaN fails too */
        if (!(value >= min && value <= max))
            return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                  "%s: array \"%s\": element %llu is %g, not a finite number in "
                                  "[%g, %g]",
                                  name, array->name, (unsigned long long)i, value, min, max);
    }
    return MESO_OK;
}

/* ---- Helpers shared by the kinds (bake_internal.h) ---------------------------------------- */

bool meso_bake_params_number(const char *json, const char *key, double *out) {
    if (!json) return false;
    char pattern[64];
    snprintf(pattern, sizeof(pattern), "\"%s\":", key);
    const char *p = strstr(json, pattern);
    if (!p) return false;
    char *end = NULL;
    double v = strtod(p + strlen(pattern), &end);
    if (end == p + strlen(pattern) || !isfinite(v)) return false;
    *out = v;
    return true;
}

const void *meso_bake_file_expect(const meso_bake_file *bake, const char *name, meso_bake_type type,
                                  int num_dims, const uint64_t *dims) {
    const meso_bake_array *a = meso_bake_file_find(bake, name);
    if (!a || a->type != type || a->num_dims != num_dims) return NULL;
    for (int i = 0; i < num_dims; i++)
        if (a->dims[i] != dims[i]) return NULL;
    return a->data;
}

void meso_bake_round_to_halves(float *values, uint16_t *out_halves, size_t count) {
    for (size_t i = 0; i < count; i++) {
        out_halves[i] = meso_half_from_float(values[i]);
        values[i] = meso_half_to_float(out_halves[i]);
    }
}

void meso_bake_halves_to_floats(const uint16_t *halves, float *out_values, size_t count) {
    for (size_t i = 0; i < count; i++) out_values[i] = meso_half_to_float(halves[i]);
}
