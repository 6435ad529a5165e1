/* Programs: the shader files put together (meso.vert; the technique's .frag after the files
 * its first line requires), compiled and linked, with the compiler's log given back as
 * "shaders/<file>:<line>: <message>" so an error points into the file, not into the
 * concatenation. Each file k is preceded by `#line <(k + 1) * 10000 + 1> <k>`: drivers that
 * report the source-string number give k, and those that do not (Mesa 22 reports 0) give a
 * line number whose ten-thousands say k. */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gl_internal.h"
#include "meso/runtime.h"

#define GL_MAX_SHADER_FILES 8
#define GL_SHADER_MAX_BYTES (1u << 20) /* a shader file read from --shader-dir */
#define GL_REQUIRES_TAG "// meso:requires"
#define GL_LINES_PER_FILE 10000 /* no shader file is longer */

const char *gl_shader_builtin(const char *name) {
    for (size_t i = 0; i < gl_embedded_shader_count; i++)
        if (strcmp(gl_embedded_shaders[i].name, name) == 0) return gl_embedded_shaders[i].text;
    return NULL;
}

/* The files of one stage, in order, with their text (owned when read from a folder). */
typedef struct shader_files {
    int count;
    char names[GL_MAX_SHADER_FILES][64];
    const char *texts[GL_MAX_SHADER_FILES];
    char *owned[GL_MAX_SHADER_FILES];
} shader_files;

static void shader_files_release(shader_files *files) {
    for (int i = 0; i < files->count; i++) free(files->owned[i]);
    files->count = 0;
}

static meso_result shader_files_add(meso_context *ctx, shader_files *files, const char *name,
                                    size_t name_length, const char *shader_dir) {
    if (files->count == GL_MAX_SHADER_FILES || name_length >= sizeof files->names[0])
        return meso_log_error(ctx, MESO_ERROR_LIMIT,
                              "shaders/%.*s: more than %d files or a name "
                              "longer than 63 characters",
                              (int)name_length, name, GL_MAX_SHADER_FILES);
    int k = files->count;
    memcpy(files->names[k], name, name_length);
    files->names[k][name_length] = 0;
    files->owned[k] = NULL;
    if (shader_dir) {
        char path[4096];
        if (snprintf(path, sizeof path, "%s/%s", shader_dir, files->names[k]) >= (int)sizeof path)
            return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: path too long",
                                  shader_dir);
        size_t size = 0;
        meso_result r = meso_file_read(ctx, path, GL_SHADER_MAX_BYTES, &files->owned[k], &size);
        if (r != MESO_OK) return r;
        files->texts[k] = files->owned[k];
    } else {
        files->texts[k] = gl_shader_builtin(files->names[k]);
        if (!files->texts[k])
            return meso_log_error(ctx, MESO_ERROR_UNSUPPORTED,
                                  "shaders/%s: no such shader built in", files->names[k]);
    }
    files->count++;
    return MESO_OK;
}

/* The files a stage's main file names on its first line, then the file itself. */
static meso_result shader_files_collect(meso_context *ctx, const char *main_name,
                                        const char *shader_dir, shader_files *files) {
    shader_files main_only = {0};
    meso_result r = shader_files_add(ctx, &main_only, main_name, strlen(main_name), shader_dir);
    if (r != MESO_OK) return r;
    const char *text = main_only.texts[0];
    if (strncmp(text, GL_REQUIRES_TAG, strlen(GL_REQUIRES_TAG)) == 0) {
        const char *p = text + strlen(GL_REQUIRES_TAG);
        while (*p && *p != '\n') {
            while (*p == ' ' || *p == '\t') p++;
            const char *start = p;
            while (*p && !isspace((unsigned char)*p)) p++;
            if (p > start && (r = shader_files_add(ctx, files, start, (size_t)(p - start),
                                                   shader_dir)) != MESO_OK)
                goto done;
        }
    }
    r = shader_files_add(ctx, files, main_name, strlen(main_name), shader_dir);
done:
    shader_files_release(&main_only);
    return r;
}

/* Rewrite the compiler's log: "<k>:<line>(<column>): <message>" (Mesa), "<k>(<line>) :
 * <message>" (NVIDIA) and "ERROR: <k>:<line>: <message>" (AMD, glslang) become
 * "<dir>/<file k>:<line>: <message>"; lines joined by "; " (one message line). */
static void format_log(const char *log, const shader_files *files, const char *dir, char *out,
                       size_t size) {
    size_t used = 0;
    out[0] = 0;
    for (const char *line = log; *line && used + 1 < size;) {
        const char *end = strchr(line, '\n');
        size_t length = end ? (size_t)(end - line) : strlen(line);
        const char *p = line;
        if (strncmp(p, "ERROR: ", 7) == 0) p += 7;
        if (strncmp(p, "WARNING: ", 9) == 0) p += 9;
        char *after = NULL;
        long k = strtol(p, &after, 10), number = -1;
        if (after != p && (*after == ':' || *after == '(')) {
            const char *q = after + 1;
            number = strtol(q, &after, 10);
            if (after == q) number = -1;
            while (*after && *after != ':' && after < line + length) after++;
            if (*after == ':') after++;
            while (*after == ' ') after++;
        }
        int w;
        if (number >= GL_LINES_PER_FILE) {
            k = number / GL_LINES_PER_FILE - 1;
            number %= GL_LINES_PER_FILE;
        }
        if (number >= 0 && k >= 0 && k < files->count)
            w = snprintf(out + used, size - used, "%s%s/%s:%ld: %.*s", used ? "; " : "", dir,
                         files->names[k], number, (int)(line + length - after), after);
        else if (length > 0)
            w = snprintf(out + used, size - used, "%s%.*s", used ? "; " : "", (int)length, line);
        else
            w = 0;
        if (w < 0) break;
        used += (size_t)w < size - used ? (size_t)w : size - used - 1;
        line = end ? end + 1 : line + length;
    }
}

static meso_result compile_stage(meso_context *ctx, GLenum stage, const shader_files *files,
                                 const char *shader_dir, GLuint *out_shader) {
    /* "#version" first, then each file after a #line naming it */
    const char *strings[2 * GL_MAX_SHADER_FILES + 1];
    char lines[GL_MAX_SHADER_FILES][32];
    int n = 0;
    strings[n++] = "#version 330 core\n";
    for (int k = 0; k < files->count; k++) {
        /* the leading \n: a file may not end with one */
        snprintf(lines[k], sizeof lines[k], "\n#line %d %d\n", (k + 1) * GL_LINES_PER_FILE + 1, k);
        strings[n++] = lines[k];
        strings[n++] = files->texts[k];
    }
    GLuint shader = glCreateShader(stage);
    glShaderSource(shader, n, strings, NULL);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096], message[4096];
        glGetShaderInfoLog(shader, sizeof log, NULL, log);
        format_log(log, files, shader_dir ? shader_dir : "shaders", message, sizeof message);
        glDeleteShader(shader);
        return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s", message);
    }
    *out_shader = shader;
    return MESO_OK;
}

meso_result gl_program_build(meso_context *ctx, const char *technique, const char *shader_dir,
                             GLuint *out_program) {
    *out_program = 0;
    char frag_name[80];
    if (snprintf(frag_name, sizeof frag_name, "%s.frag", technique) >= (int)sizeof frag_name)
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT, "%s: name too long", technique);
    shader_files vert = {0}, frag = {0};
    GLuint vs = 0, fs = 0, program = 0;
    meso_result r;
    if ((r = shader_files_collect(ctx, "meso.vert", shader_dir, &vert)) != MESO_OK ||
        (r = shader_files_collect(ctx, frag_name, shader_dir, &frag)) != MESO_OK ||
        (r = compile_stage(ctx, GL_VERTEX_SHADER, &vert, shader_dir, &vs)) != MESO_OK ||
        (r = compile_stage(ctx, GL_FRAGMENT_SHADER, &frag, shader_dir, &fs)) != MESO_OK)
        goto done;
    program = glCreateProgram();
    glAttachShader(program, vs);
    glAttachShader(program, fs);
    glLinkProgram(program);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[4096];
        glGetProgramInfoLog(program, sizeof log, NULL, log);
        for (char *c = log; *c; c++)
            if (*c == '\n') *c = ' ';
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "shaders/%s: link: %s", frag_name, log);
        glDeleteProgram(program);
        goto done;
    }
    *out_program = program;
done:
    if (vs) glDeleteShader(vs);
    if (fs) glDeleteShader(fs);
    shader_files_release(&vert);
    shader_files_release(&frag);
    return r;
}
