/* Screening of mesh files before assimp reads them.
 *
 * assimp trusts what a file declares: a 262-byte PLY whose header declares 67 M faces made it
 * allocate 8 GB, and a glTF buffer may name any local file (/etc/passwd, /dev/urandom). So
 * every format with declared sizes is checked here against the file's real size first:
 *   PLY   every element's count times the least bytes one element can take (binary: its
 *         scalar sizes and list counts; ASCII: two characters a value) must fit after the
 *         header; the header must end with an end_header line (assimp 5.2 loops forever
 *         without one).
 *   glTF  (JSON or GLB) buffers are the GLB's binary chunk, data: URIs or files beside the
 *         glTF (no absolute paths, no "..", no URI schemes, regular files only); each buffer's
 *         byteLength must fit in its data, each bufferView in its buffer, each accessor in its
 *         bufferView; accessors without data are bounded by the mesh limits.
 *   OBJ   has no declared counts (what assimp builds grows with the file); the material
 *         libraries it names (mtllib), which meso reads itself (geom_mtl.c), follow the rule of
 *         glTF buffers (beside the OBJ) and must be regular files when they exist; an mtllib
 *         line with a NUL byte is refused.
 */
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <cjson/cJSON.h>

#include "geom_internal.h"
#include "meso/runtime.h"

/* A PLY header longer than this is refused (real headers are a few hundred bytes). */
#define PLY_HEADER_MAX 65536
/* glTF JSON larger than this is refused before parsing. */
#define GLTF_JSON_MAX (64u << 20)

/* ---- PLY ---------------------------------------------------------------------------------- */

static unsigned ply_type_size(const char *type) {
    static const struct {
        const char *name;
        unsigned size;
    } types[] = {{"char", 1},  {"int8", 1},    {"uchar", 1},  {"uint8", 1},
                 {"short", 2}, {"int16", 2},   {"ushort", 2}, {"uint16", 2},
                 {"int", 4},   {"int32", 4},   {"uint", 4},   {"uint32", 4},
                 {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
    for (size_t i = 0; i < sizeof(types) / sizeof(types[0]); i++)
        if (!strcmp(types[i].name, type)) return types[i].size;
    return 0;
}

typedef struct ply_element {
    char name[32];
    unsigned long long count;
    unsigned long long least_bytes; /* the fewest bytes one element can take */
} ply_element;

/* The offset just past the "end_header" line, or 0 when the buffer has none. The header is
 * text: it is searched as a string up to the first NUL, for a line that is "end_header" (a
 * token assimp can see), not merely containing it. */
static size_t ply_header_end(const char *buffer) {
    for (const char *at = strstr(buffer, "end_header"); at; at = strstr(at + 1, "end_header")) {
        const char *line = at;
        while (line > buffer && (line[-1] == ' ' || line[-1] == '\t')) line--;
        const char *after = at + 10;
        while (*after == ' ' || *after == '\t') after++;
        bool line_start = line > buffer && (line[-1] == '\n' || line[-1] == '\r');
        if (!line_start) continue;
        if (*after == '\r') after++;
        if (*after == '\n')
            after++;
        else if (*after != 0)
            continue;
        return (size_t)(after - buffer);
    }
    return 0;
}

/* ASCII PLY data: every value a number (a sign, digits, a point, an exponent). assimp 5.2's
 * ASCII PLY parser leaks the element it was building when a value is not a number; meso
 * refuses such a file before assimp reads it, naming the line. */
static meso_result screen_ply_ascii_values(meso_context *ctx, const char *path, FILE *file,
                                           size_t header_size) {
    if (fseeko(file, (off_t)header_size, SEEK_SET) != 0)
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot seek: %s", path, strerror(errno));
    char token[64];
    size_t token_length = 0;
    unsigned long long line = 1;
    bool bad = false;
    for (int c = getc(file);; c = getc(file)) {
        bool blank = c == EOF || c == ' ' || c == '\t' || c == '\n' || c == '\r';
        if (!blank) {
            bad = token_length + 1 >= sizeof token || !strchr("0123456789+-.eE", c) || c == 0;
            if (bad) break;
            token[token_length++] = (char)c;
            continue;
        }
        if (token_length > 0) {
            token[token_length] = 0;
            char *end = NULL;
            strtod(token, &end);
            bad = end != token + token_length;
            if (bad) break;
            token_length = 0;
        }
        if (c == '\n') line++;
        if (c == EOF) break;
    }
    if (bad)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: PLY data line %llu: a value that is not a number", path, line);
    return MESO_OK;
}

static meso_result screen_ply(meso_context *ctx, const char *path, char *buffer, uint64_t file_size,
                              FILE *file) {
    size_t header_size = ply_header_end(buffer);
    if (header_size == 0)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: PLY header has no end_header in its first %d bytes", path,
                              PLY_HEADER_MAX);
    buffer[header_size] = 0;
    bool binary = false;
    ply_element elements[64];
    int num_elements = 0;
    char *save = NULL;
    for (char *line = strtok_r(buffer, "\r\n", &save); line; line = strtok_r(NULL, "\r\n", &save)) {
        char word[4][32] = {{0}};
        unsigned long long count = 0;
        int n = sscanf(line, "%31s %31s %31s %31s", word[0], word[1], word[2], word[3]);
        if (n >= 2 && !strcmp(word[0], "format")) {
            binary = strncmp(word[1], "binary", 6) == 0;
        } else if (n >= 1 && !strcmp(word[0], "element")) {
            if (num_elements == 64)
                return meso_log_error(ctx, MESO_ERROR_LIMIT, "%s: more than 64 PLY elements", path);
            char *end = NULL;
            errno = 0;
            if (n >= 3) count = strtoull(word[2], &end, 10);
            if (n < 3 || errno || end == word[2] || *end || word[2][0] == '-')
                return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: PLY: bad element line '%.40s'",
                                      path, line);
            ply_element *e = &elements[num_elements++];
            snprintf(e->name, sizeof(e->name), "%s", word[1]);
            e->count = count;
            e->least_bytes = 0;
        } else if (n >= 1 && !strcmp(word[0], "property")) {
            if (num_elements == 0)
                return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: PLY: property before element",
                                      path);
            bool list = n >= 2 && !strcmp(word[1], "list");
            unsigned size = ply_type_size(list ? word[2] : word[1]);
            if (size == 0)
                return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                      "%s: PLY: unknown property type in '%.40s'", path, line);
            /* A list may be empty, so only its count is sure to be there. ASCII: a digit and a
             * separator per value at least. */
            elements[num_elements - 1].least_bytes += binary ? size : 2;
        }
    }
    /* The limits first: a count over them is refused whatever the file holds. */
    for (int i = 0; i < num_elements; i++) {
        if (!strcmp(elements[i].name, "vertex") && elements[i].count > MESO_MESH_MAX_VERTICES)
            return meso_log_error(ctx, MESO_ERROR_LIMIT, "%s: %llu vertices exceed the limit %u",
                                  path, elements[i].count, MESO_MESH_MAX_VERTICES);
        if (!strcmp(elements[i].name, "face") && elements[i].count > MESO_MESH_MAX_TRIANGLES)
            return meso_log_error(ctx, MESO_ERROR_LIMIT, "%s: %llu faces exceed the limit %u", path,
                                  elements[i].count, MESO_MESH_MAX_TRIANGLES);
    }
    /* Counts above 2^40 (a terabyte of data at least) saturate, so the sums cannot wrap. */
    const unsigned long long saturated = 1ull << 40;
    uint64_t data_size = file_size > header_size ? file_size - header_size : 0;
    unsigned long long declared = 0;
    for (int i = 0; i < num_elements; i++) {
        const ply_element *e = &elements[i];
        unsigned long long least = e->least_bytes ? e->least_bytes : 1;
        declared += e->count > saturated ? saturated : e->count * least;
    }
    /* ASCII: the last value may lack its separator. */
    if (!binary && declared > 0) declared -= 1;
    if (declared > data_size)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: truncated PLY: header declares %s%llu bytes, file has %llu",
                              path, declared >= saturated ? "over " : "", declared + header_size,
                              (unsigned long long)file_size);
    return binary ? MESO_OK : screen_ply_ascii_values(ctx, path, file, header_size);
}

/* ---- OBJ ---------------------------------------------------------------------------------- */

bool geom_resolve_beside(const char *path, const char *name, char *out, size_t out_size) {
    const char *slash = strrchr(path, '/');
    int folder = name[0] == '/' || !slash ? 0 : (int)(slash - path) + 1;
    int written = snprintf(out, out_size, "%.*s%s", folder, path, name);
    return written >= 0 && (size_t)written < out_size;
}

static meso_result screen_obj(meso_context *ctx, const char *path, FILE *file) {
    rewind(file);
    char *line = NULL;
    size_t capacity = 0;
    ssize_t length;
    meso_result r = MESO_OK;
    for (long number = 1; r == MESO_OK && (length = getline(&line, &capacity, file)) > 0;
         number++) {
        if (strncmp(line, "mtllib", 6) != 0 || (line[6] != ' ' && line[6] != '\t')) continue;
        if (memchr(line, 0, (size_t)length)) {
            r = meso_log_error(ctx, MESO_ERROR_FORMAT,
                               "%s: line %ld: mtllib: a NUL byte in the name", path, number);
            break;
        }
        char *save = NULL;
        for (char *name = strtok_r(line + 7, " \t\r\n", &save); name && r == MESO_OK;
             name = strtok_r(NULL, " \t\r\n", &save)) {
            char full[PATH_MAX];
            struct stat st;
            if (!geom_name_is_beside(name))
                r = meso_log_error(ctx, MESO_ERROR_FORMAT,
                                   "%s: mtllib %s: must name a file beside the mesh (no absolute "
                                   "path, no '..', no scheme)",
                                   path, name);
            else if (!geom_resolve_beside(path, name, full, sizeof(full)) || stat(full, &st) != 0)
                continue; /* missing: the mesh has no material from it */
            else if (!S_ISREG(st.st_mode))
                r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: mtllib %s is not a regular file",
                                   path, full);
        }
    }
    free(line);
    return r;
}

/* ---- glTF --------------------------------------------------------------------------------- */

static uint32_t read_le32(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* A non-negative integer member of object, or `fallback` when absent; -1 when malformed. */
static double json_number(const cJSON *object, const char *name, double fallback) {
    const cJSON *item = cJSON_GetObjectItemCaseSensitive(object, name);
    if (!item) return fallback;
    if (!cJSON_IsNumber(item) || !(item->valuedouble >= 0.0) || item->valuedouble > 1e18 ||
        item->valuedouble != (double)(long long)item->valuedouble)
        return -1.0;
    return item->valuedouble;
}

bool geom_name_is_beside(const char *uri) {
    if (!uri[0] || uri[0] == '/' || strchr(uri, '\\') || strchr(uri, ':')) return false;
    for (const char *part = uri; part;) {
        const char *slash = strchr(part, '/');
        size_t length = slash ? (size_t)(slash - part) : strlen(part);
        if (length == 2 && part[0] == '.' && part[1] == '.') return false;
        part = slash ? slash + 1 : NULL;
    }
    /* percent-escapes could spell ".." or "/" again once decoded */
    return strstr(uri, "%2e") == NULL && strstr(uri, "%2E") == NULL && strstr(uri, "%2f") == NULL &&
           strstr(uri, "%2F") == NULL;
}

/* The size of buffer `index`'s data: the GLB binary chunk, a data: URI's length (an upper
 * bound of its decoded size), or a regular file beside the glTF. */
static meso_result gltf_buffer_data_size(meso_context *ctx, const char *path, const cJSON *buffer,
                                         int index, int64_t glb_binary_size, double *out_size) {
    const cJSON *uri = cJSON_GetObjectItemCaseSensitive(buffer, "uri");
    if (!uri) {
        if (glb_binary_size < 0)
            return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                  "%s: buffers[%d]: no uri and no GLB "
                                  "binary chunk",
                                  path, index);
        *out_size = (double)glb_binary_size;
        return MESO_OK;
    }
    if (!cJSON_IsString(uri))
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: buffers[%d].uri: not a string", path,
                              index);
    const char *text = uri->valuestring;
    if (!strncmp(text, "data:", 5)) {
        *out_size = (double)strlen(text);
        return MESO_OK;
    }
    if (!geom_name_is_beside(text))
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: buffers[%d].uri: must name a file beside the glTF (no "
                              "absolute path, no '..', no scheme)",
                              path, index);
    char full[PATH_MAX];
    if (!geom_resolve_beside(path, text, full, sizeof(full)))
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: buffers[%d].uri: too long", path, index);
    struct stat st;
    if (stat(full, &st) != 0)
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: buffers[%d].uri: %s: %s", path, index, full,
                              strerror(errno));
    if (!S_ISREG(st.st_mode))
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: buffers[%d].uri: %s is not a regular file", path, index, full);
    *out_size = (double)st.st_size;
    return MESO_OK;
}

static meso_result screen_gltf_json(meso_context *ctx, const char *path, const char *json,
                                    size_t json_size, int64_t glb_binary_size) {
    cJSON *root = cJSON_ParseWithLength(json, json_size);
    if (!root) return MESO_OK; /* not JSON: assimp says why */
    meso_result r = MESO_OK;
    const cJSON *buffers = cJSON_GetObjectItemCaseSensitive(root, "buffers");
    const cJSON *views = cJSON_GetObjectItemCaseSensitive(root, "bufferViews");
    const cJSON *accessors = cJSON_GetObjectItemCaseSensitive(root, "accessors");
    int num_buffers = cJSON_IsArray(buffers) ? cJSON_GetArraySize(buffers) : 0;
    int num_views = cJSON_IsArray(views) ? cJSON_GetArraySize(views) : 0;
    double *buffer_sizes = calloc((size_t)num_buffers + 1, sizeof(double));
    double *view_sizes = calloc((size_t)num_views + 1, sizeof(double));
    if (!buffer_sizes || !view_sizes) {
        r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
        goto done;
    }
    for (int i = 0; i < num_buffers && r == MESO_OK; i++) {
        const cJSON *buffer = cJSON_GetArrayItem(buffers, i);
        double declared = json_number(buffer, "byteLength", -1.0), available = 0.0;
        if (declared < 0.0) {
            r = meso_log_error(ctx, MESO_ERROR_FORMAT,
                               "%s: buffers[%d].byteLength: missing or "
                               "not a size",
                               path, i);
            break;
        }
        r = gltf_buffer_data_size(ctx, path, buffer, i, glb_binary_size, &available);
        if (r == MESO_OK && declared > available)
            r = meso_log_error(ctx, MESO_ERROR_FORMAT,
                               "%s: truncated glTF: buffers[%d] declares %.0f bytes, its data has "
                               "%.0f",
                               path, i, declared, available);
        buffer_sizes[i] = declared;
    }
    for (int i = 0; i < num_views && r == MESO_OK; i++) {
        const cJSON *view = cJSON_GetArrayItem(views, i);
        double buffer = json_number(view, "buffer", -1.0),
               offset = json_number(view, "byteOffset", 0),
               length = json_number(view, "byteLength", -1.0);
        if (buffer < 0.0 || buffer >= num_buffers || offset < 0.0 || length < 0.0 ||
            offset + length > buffer_sizes[(int)buffer])
            r = meso_log_error(ctx, MESO_ERROR_FORMAT,
                               "%s: bufferViews[%d]: does not fit in its buffer", path, i);
        else
            view_sizes[i] = length;
    }
    int num_accessors = cJSON_IsArray(accessors) ? cJSON_GetArraySize(accessors) : 0;
    for (int i = 0; i < num_accessors && r == MESO_OK; i++) {
        const cJSON *accessor = cJSON_GetArrayItem(accessors, i);
        double count = json_number(accessor, "count", -1.0);
        double view = json_number(accessor, "bufferView", -2.0);
        double offset = json_number(accessor, "byteOffset", 0.0);
        if (count < 0.0 || view == -1.0 || offset < 0.0 || view >= num_views) {
            r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: accessors[%d]: bad count or bufferView",
                               path, i);
        } else if (view == -2.0) {
            /* no data: assimp fills count zeros, bounded here like a mesh */
            if (count > 3.0 * MESO_MESH_MAX_TRIANGLES)
                r = meso_log_error(ctx, MESO_ERROR_LIMIT,
                                   "%s: accessors[%d]: count %.0f exceeds "
                                   "the limit %u",
                                   path, i, count, 3u * MESO_MESH_MAX_TRIANGLES);
        } else if (count > 0.0 && offset + count > view_sizes[(int)view]) {
            /* every element takes at least one byte */
            r = meso_log_error(ctx, MESO_ERROR_FORMAT,
                               "%s: truncated glTF: accessors[%d] declares %.0f elements, its "
                               "bufferView has %.0f bytes",
                               path, i, count, view_sizes[(int)view]);
        }
    }
done:
    free(buffer_sizes);
    free(view_sizes);
    cJSON_Delete(root);
    return r;
}

/* GLB: a 12-byte header ("glTF", version, length), a JSON chunk, an optional BIN chunk. */
static meso_result screen_glb(meso_context *ctx, const char *path, FILE *file, uint64_t file_size) {
    unsigned char header[20];
    rewind(file);
    if (fread(header, 1, 20, file) != 20)
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: truncated GLB header", path);
    uint32_t length = read_le32(header + 8), json_length = read_le32(header + 12);
    if (length != file_size)
        return meso_log_error(ctx, MESO_ERROR_FORMAT,
                              "%s: truncated GLB: header declares %u bytes, file has %llu", path,
                              (unsigned)length, (unsigned long long)file_size);
    if (memcmp(header + 16, "JSON", 4) != 0 || json_length > file_size - 20 ||
        json_length > GLTF_JSON_MAX)
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: GLB: bad JSON chunk", path);
    char *json = malloc((size_t)json_length + 1);
    if (!json) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    if (fread(json, 1, json_length, file) != json_length) {
        free(json);
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: truncated GLB JSON chunk", path);
    }
    json[json_length] = 0;
    int64_t binary_size = -1;
    uint64_t binary_at = 20 + (uint64_t)json_length;
    unsigned char chunk[8];
    if (binary_at + 8 <= file_size && fread(chunk, 1, 8, file) == 8 &&
        !memcmp(chunk + 4, "BIN", 4)) {
        binary_size = read_le32(chunk);
        if ((uint64_t)binary_size > file_size - binary_at - 8) {
            free(json);
            return meso_log_error(ctx, MESO_ERROR_FORMAT,
                                  "%s: truncated GLB: binary chunk declares %lld bytes, file has "
                                  "%llu after it",
                                  path, (long long)binary_size,
                                  (unsigned long long)(file_size - binary_at - 8));
        }
    }
    meso_result r = screen_gltf_json(ctx, path, json, json_length, binary_size);
    free(json);
    return r;
}

static bool ends_with_ignoring_case(const char *text, const char *suffix) {
    size_t n = strlen(text), m = strlen(suffix);
    if (m > n) return false;
    for (size_t i = 0; i < m; i++)
        if (tolower((unsigned char)text[n - m + i]) != suffix[i]) return false;
    return true;
}

/* ---- Entry -------------------------------------------------------------------------------- */

meso_result geom_screen_mesh_file(meso_context *ctx, const char *path, FILE *file,
                                  geom_mesh_kind *out_kind) {
    *out_kind = GEOM_MESH_OTHER;
    struct stat st;
    if (fstat(fileno(file), &st) != 0)
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot stat: %s", path, strerror(errno));
    uint64_t file_size = (uint64_t)st.st_size;
    char *buffer = malloc(PLY_HEADER_MAX + 1);
    if (!buffer) return meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
    size_t size = fread(buffer, 1, PLY_HEADER_MAX, file);
    buffer[size] = 0;
    meso_result r = MESO_OK;
    /* Recognised by content, as assimp does; glTF JSON by its extension (JSON has no magic). */
    bool is_ply = size >= 3 && tolower((unsigned char)buffer[0]) == 'p' &&
                  tolower((unsigned char)buffer[1]) == 'l' &&
                  tolower((unsigned char)buffer[2]) == 'y';
    if (is_ply) {
        *out_kind = GEOM_MESH_PLY;
        r = screen_ply(ctx, path, buffer, file_size, file);
    } else if (size >= 4 && !memcmp(buffer, "glTF", 4)) {
        *out_kind = GEOM_MESH_GLTF;
        r = screen_glb(ctx, path, file, file_size);
    } else if (ends_with_ignoring_case(path, ".obj")) {
        *out_kind = GEOM_MESH_OBJ;
        r = screen_obj(ctx, path, file);
    } else if (ends_with_ignoring_case(path, ".gltf")) {
        *out_kind = GEOM_MESH_GLTF;
        if (file_size > GLTF_JSON_MAX) {
            r = meso_log_error(ctx, MESO_ERROR_LIMIT, "%s: glTF JSON over %u bytes", path,
                               GLTF_JSON_MAX);
        } else {
            char *json = realloc(buffer, (size_t)file_size + 1);
            if (!json) {
                r = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", path);
            } else {
                buffer = json;
                rewind(file);
                size = fread(json, 1, (size_t)file_size, file);
                r = screen_gltf_json(ctx, path, json, size, -1);
            }
        }
    }
    free(buffer);
    return r;
}
