/* OBJ material libraries (MTL), read by meso rather than by assimp.
 *
 * assimp 5.2's MTL parser dereferences a null material for any statement before the first
 * `newmtl` (a one-line `map_Kd x.png` crashes the process), leaks on a one-byte file, and
 * opens whatever path an `mtllib` names. So assimp reads an OBJ's geometry only (geom_import.c
 * lets it open no file but the OBJ itself; an unknown `usemtl` name becomes an empty material
 * of that name) and this small reader takes what meso uses from the material of that name:
 * the diffuse colour (Kd), its texture (map_Kd) and the normal texture (norm, map_Kn), and
 * lists the other textures as ignored. Libraries follow the rule of glTF buffers: a file
 * beside the OBJ or below its folder (no absolute path, no "..", no scheme), a regular file,
 * at most GEOM_MTL_MAX_BYTES; when none defines the material, "<the OBJ's name>.mtl" beside it
 * is read, as assimp does. A statement outside a material is ignored; a line is at most 4 KiB
 * (longer ones are ignored).
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "geom_internal.h"
#include "meso/runtime.h"

#define MTL_LINE_MAX 4096

static const char *skip_blanks(const char *p) {
    while (*p == ' ' || *p == '\t') p++;
    return p;
}

/* The keyword at p (up to a blank) equals `word`, case-insensitively as assimp compares. */
static bool keyword_is(const char *p, size_t length, const char *word) {
    return strlen(word) == length && strncasecmp(p, word, length) == 0;
}

/* Kd r [g b]: one value is grey; "Kd spectral" and "Kd xyz" are not colours meso reads. */
static void read_color(const char *p, meso_mesh_material *m) {
    float rgb[3];
    int n = 0;
    for (; n < 3; n++) {
        p = skip_blanks(p);
        char *end = NULL;
        rgb[n] = strtof(p, &end);
        if (end == p) break;
        p = end;
    }
    if (n == 1) rgb[1] = rgb[2] = rgb[0];
    if ((n != 1 && n != 3) || !isfinite(rgb[0]) || !isfinite(rgb[1]) || !isfinite(rgb[2])) return;
    m->has_color = true;
    m->color = (meso_vec3){meso_clampf(rgb[0], 0.0f, 1.0f), meso_clampf(rgb[1], 0.0f, 1.0f),
                           meso_clampf(rgb[2], 0.0f, 1.0f)};
}

static bool is_number(const char *p, size_t length) {
    char *end = NULL;
    strtod(p, &end);
    return end == p + length && length > 0;
}

/* The file name of a texture statement: the rest of the line after its options (-bm 1,
 * -clamp on, -mm base gain, -o u [v [w]] ...: one value each, two for -mm, up to three
 * numbers for -o, -s and -t). */
static const char *texture_name(const char *p) {
    p = skip_blanks(p);
    while (*p == '-') {
        size_t length = strcspn(p, " \t");
        bool vector = length == 2 && (p[1] == 'o' || p[1] == 's' || p[1] == 't');
        int values = vector ? 3 : length == 3 && !strncmp(p, "-mm", 3) ? 2 : 1;
        p = skip_blanks(p + length);
        for (int v = 0; v < values && *p; v++) {
            size_t token = strcspn(p, " \t");
            if (vector && v > 0 && !is_number(p, token)) break;
            p = skip_blanks(p + token);
        }
    }
    return p;
}

static void read_texture(const char *p, const char *what, char *out, meso_mesh_material *m) {
    const char *name = texture_name(p);
    size_t length = strlen(name);
    while (length > 0 && (name[length - 1] == ' ' || name[length - 1] == '\t')) length--;
    if (length == 0) return;
    char ignored[96];
    if (length >= MESO_MESH_MATERIAL_PATH_MAX) {
        snprintf(ignored, sizeof ignored, "%s (path too long)", what);
        geom_material_ignore(m, ignored);
        return;
    }
    memcpy(out, name, length);
    out[length] = 0;
}

/* One statement of the wanted material. */
static void read_statement(const char *line, meso_mesh_material *m) {
    size_t length = strcspn(line, " \t");
    const char *rest = line + length;
    static const struct {
        const char *keyword, *what;
    } unused[] = {{"map_Ks", "specular texture"},       {"map_Ke", "emissive texture"},
                  {"map_emissive", "emissive texture"}, {"map_bump", "bump/height texture"},
                  {"bump", "bump/height texture"},      {"map_d", "opacity texture"},
                  {"map_Pm", "metallic texture"},       {"map_Pr", "roughness texture"}};
    if (keyword_is(line, length, "Kd")) {
        read_color(rest, m);
    } else if (keyword_is(line, length, "map_Kd")) {
        read_texture(rest, "base colour texture", m->color_map, m);
    } else if (keyword_is(line, length, "norm") || keyword_is(line, length, "map_Kn")) {
        read_texture(rest, "normal texture", m->normal_map, m);
    } else {
        for (size_t u = 0; u < sizeof(unused) / sizeof(unused[0]); u++)
            if (keyword_is(line, length, unused[u].keyword))
                geom_material_ignore(m, unused[u].what);
    }
}

/* Look for material `name` in the library text; true when it was found (and read). */
static bool read_library(const char *text, size_t size, const char *name, meso_mesh_material *m) {
    bool inside = false, found = false;
    char line[MTL_LINE_MAX];
    for (size_t at = 0; at < size;) {
        const char *start = text + at;
        const char *newline = memchr(start, '\n', size - at);
        size_t length = newline ? (size_t)(newline - start) : size - at;
        at += length + 1;
        if (length >= sizeof line) continue;
        memcpy(line, start, length);
        line[length] = 0; /* a NUL inside ends the line early: what follows is not read */
        for (char *c = line; *c; c++)
            if (*c == '\r') *c = ' ';
        const char *p = skip_blanks(line);
        size_t end = strlen(p);
        while (end > 0 && p[end - 1] == ' ') end--;
        line[(size_t)(p - line) + end] = 0;
        size_t word = strcspn(p, " \t");
        if (keyword_is(p, word, "newmtl")) {
            if (found) return true; /* the first definition of the name is the one read */
            inside = strcmp(skip_blanks(p + word), name) == 0;
            found = inside;
            continue;
        }
        if (inside) read_statement(p, m);
    }
    return found;
}

meso_result geom_obj_read_material(meso_context *ctx, const char *path, FILE *obj, const char *name,
                                   meso_mesh_material *out) {
    memset(out, 0, sizeof(*out));
    rewind(obj);
    char *line = NULL;
    size_t capacity = 0;
    ssize_t length;
    meso_result r = MESO_OK;
    bool found = false;
    while (!found && r == MESO_OK && (length = getline(&line, &capacity, obj)) > 0) {
        if (strncmp(line, "mtllib", 6) != 0 || (line[6] != ' ' && line[6] != '\t')) continue;
        line[strcspn(line, "\r\n")] = 0; /* the screen refused NUL bytes on these lines */
        char *save = NULL;
        for (char *library = strtok_r(line + 7, " \t", &save); library && !found && r == MESO_OK;
             library = strtok_r(NULL, " \t", &save)) {
            char full[PATH_MAX];
            struct stat st;
            if (!geom_resolve_beside(path, library, full, sizeof full) || stat(full, &st) != 0)
                continue; /* missing: no material from it, as before */
            char *text = NULL;
            size_t size = 0;
            r = meso_file_read(ctx, full, GEOM_MTL_MAX_BYTES, &text, &size);
            if (r == MESO_OK) found = read_library(text, size, name, out);
            free(text);
        }
    }
    free(line);
    /* as assimp does: a library that defines nothing of the name, or is missing, is looked for
     * once more as the OBJ's own name with .mtl ("model.obj" -> "model.mtl") */
    size_t length_of_path = strlen(path);
    char fallback[PATH_MAX];
    struct stat st;
    if (!found && r == MESO_OK && length_of_path > 4 && length_of_path < sizeof fallback &&
        strcasecmp(path + length_of_path - 4, ".obj") == 0) {
        memcpy(fallback, path, length_of_path - 3);
        memcpy(fallback + length_of_path - 3, "mtl", 4);
        if (stat(fallback, &st) == 0 && S_ISREG(st.st_mode)) {
            char *text = NULL;
            size_t size = 0;
            r = meso_file_read(ctx, fallback, GEOM_MTL_MAX_BYTES, &text, &size);
            if (r == MESO_OK) read_library(text, size, name, out);
            free(text);
        }
    }
    if (r != MESO_OK) memset(out, 0, sizeof(*out));
    return r;
}
