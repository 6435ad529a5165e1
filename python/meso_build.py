"""cffi build script of the Python package's extension, meso._meso_cffi (API mode).

API mode (docs/python.md): the declarations below are compiled against <meso/meso.h>, so the
C compiler checks each of them against the real header, and the structs declared with "...;"
take their layout from it (meso's scenes and framebuffers are plain structs the package reads
and writes field by field). Calls go straight to libmeso.so without libffi, and cffi's
generated wrappers release the GIL around every call.

Where the headers and libmeso.so are found, first match wins:
  MESO_INCLUDE_DIR / MESO_LIBRARY_DIR   set by the project's build (make python, make test)
  pkg-config libmeso                    an installed meso built with -DMESO_SHARED=ON
  ../include and ../build               the source tree, after `make build CMAKE_FLAGS=...`
Run directly (python3 meso_build.py --build-dir DIR) it compiles the extension into
DIR/meso/; setup.py runs it through setuptools (cffi_modules) for pip.
"""

import argparse
import os
import shlex
import subprocess

import cffi

HERE = os.path.dirname(os.path.abspath(__file__))

CDEF = r"""
typedef struct meso_vec2 { float x, y; } meso_vec2;
typedef struct meso_vec3 { float x, y, z; } meso_vec3;

typedef enum meso_result {
    MESO_OK, MESO_ERROR_INVALID_ARGUMENT, MESO_ERROR_IO, MESO_ERROR_FORMAT, MESO_ERROR_LIMIT,
    MESO_ERROR_OUT_OF_MEMORY, MESO_ERROR_UNSUPPORTED, MESO_ERROR_CANCELLED, MESO_ERROR_INTERNAL,
    ...
} meso_result;
const char *meso_result_string(meso_result result);
bool meso_result_is_bad_input(meso_result result);

typedef enum meso_log_level { MESO_LOG_ERROR, MESO_LOG_WARNING, MESO_LOG_INFO, ... } meso_log_level;
typedef void (*meso_log_fn)(void *user, meso_log_level level, const char *message);
typedef bool (*meso_progress_fn)(void *user, const char *label, double fraction);
typedef enum meso_progress_mode {
    MESO_PROGRESS_DEFAULT, MESO_PROGRESS_ALWAYS, MESO_PROGRESS_NEVER, ...
} meso_progress_mode;
typedef struct meso_context_desc {
    int num_threads;
    meso_log_fn log;
    void *log_user;
    meso_progress_mode progress;
    meso_progress_fn on_progress;
    void *progress_user;
    uint64_t memory_limit;
    ...;
} meso_context_desc;
typedef struct meso_context meso_context;
meso_result meso_context_create(const meso_context_desc *desc, meso_context **out_ctx);
void meso_context_destroy(meso_context *ctx);
int meso_context_num_threads(const meso_context *ctx);
void meso_context_set_num_threads(meso_context *ctx, int num_threads);
const char *meso_context_last_error(const meso_context *ctx);
uint64_t meso_context_memory_limit(const meso_context *ctx);
meso_result meso_memory_check(meso_context *ctx, const char *name, uint64_t estimate_bytes);

#define MESO_IMAGE_MAX_SIDE ...
#define MESO_IMAGE_MAX_PIXELS ...
#define MESO_SCENE_MAX_LIGHTS ...
#define MESO_OPTIONS_MAX ...
#define MESO_NAME_MAX ...
typedef enum meso_encoding {
    MESO_ENCODING_DEFAULT, MESO_ENCODING_SRGB, MESO_ENCODING_LINEAR, ...
} meso_encoding;
typedef enum meso_wrap { MESO_WRAP_DEFAULT, MESO_WRAP_REPEAT, MESO_WRAP_CLAMP, ... } meso_wrap;
typedef struct meso_image { int width, height; int channels; float *pixels; ...; } meso_image;
typedef struct meso_png_desc { int bit_depth; meso_encoding encoding; ...; } meso_png_desc;
meso_result meso_image_load_png(meso_context *ctx, const char *path, meso_image **out_image);
void meso_image_destroy(meso_image *image);

typedef struct meso_heightfield {
    int width, height; float *heights; meso_wrap wrap; uint64_t hash; ...;
} meso_heightfield;
meso_result meso_heightfield_create_from_image(meso_context *ctx, const meso_image *image,
                                               meso_wrap wrap, meso_heightfield **out_heightfield);
void meso_heightfield_destroy(meso_heightfield *heightfield);
typedef struct meso_solid meso_solid;
typedef struct meso_texture meso_texture;
typedef struct meso_environment meso_environment;
typedef struct meso_mesh {
    size_t num_vertices; size_t num_triangles;
    meso_vec3 *positions; meso_vec3 *normals; meso_vec2 *uvs; uint32_t *indices;
    ...;
} meso_mesh;

typedef enum meso_light_type { MESO_LIGHT_DIRECTIONAL, MESO_LIGHT_POINT, ... } meso_light_type;
typedef struct meso_light {
    meso_light_type type; meso_vec3 direction; meso_vec3 position; meso_vec3 color; ...;
} meso_light;
typedef struct meso_camera { meso_vec3 eye, target, up; float fov_y_deg; ...; } meso_camera;
typedef struct meso_material {
    meso_vec3 albedo; meso_texture *color_map; meso_vec3 specular; float shininess;
    meso_texture *normal_map; ...;
} meso_material;
typedef enum meso_mesostructure_kind {
    MESO_MESOSTRUCTURE_NONE, MESO_MESOSTRUCTURE_HEIGHT_FIELD, MESO_MESOSTRUCTURE_SOLID, ...
} meso_mesostructure_kind;
typedef struct meso_mesostructure {
    meso_mesostructure_kind kind; meso_heightfield *height_field; meso_solid *solid;
    float depth; float offset; meso_wrap wrap; char source[...]; ...;
} meso_mesostructure;
typedef struct meso_option { char technique[...]; char name[...]; double value; ...; } meso_option;
typedef struct meso_object {
    char name[...]; meso_mesh *mesh; meso_material material; meso_mesostructure mesostructure;
    char technique[...]; meso_option options[...]; int num_options; ...;
} meso_object;
typedef struct meso_scene {
    char path[...]; int width, height; meso_vec3 background; meso_encoding encoding;
    meso_camera camera; meso_vec3 ambient; meso_environment *environment;
    meso_light lights[...]; int num_lights; meso_object *objects; int num_objects; ...;
} meso_scene;
typedef struct meso_scene_resource {
    const char *name; const meso_image *image; meso_encoding encoding;
    const meso_vec3 *positions; size_t num_vertices; const uint32_t *indices;
    size_t num_triangles; ...;
} meso_scene_resource;
typedef struct meso_scene_desc {
    const char *json; const char *name; const char *base_dir;
    const meso_scene_resource *resources; size_t num_resources; ...;
} meso_scene_desc;
meso_result meso_scene_load(meso_context *ctx, const char *path, meso_scene **out_scene);
meso_result meso_scene_create(meso_context *ctx, const meso_scene_desc *desc,
                              meso_scene **out_scene);
void meso_scene_destroy(meso_scene *scene);

typedef struct meso_framebuffer {
    int width, height; float *color; float *coverage; float *depth; ...;
} meso_framebuffer;
meso_result meso_framebuffer_save(meso_context *ctx, const meso_framebuffer *fb,
                                  const meso_png_desc *desc, const char *path,
                                  const char *coverage_path);
typedef enum meso_technique_kind {
    MESO_TECHNIQUE_PER_PIXEL, MESO_TECHNIQUE_GEOMETRY, MESO_TECHNIQUE_REFERENCE, ...
} meso_technique_kind;
#define MESO_TECHNIQUE_ACCEPTS_NONE ...
#define MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD ...
#define MESO_TECHNIQUE_ACCEPTS_SOLID ...
typedef enum meso_option_type { MESO_OPTION_INT, MESO_OPTION_BOOL, MESO_OPTION_FLOAT, ... }
    meso_option_type;
typedef struct meso_technique_option {
    const char *name; meso_option_type type; double min, max; double default_value;
    const char *doc; ...;
} meso_technique_option;
typedef struct meso_technique_info {
    const char *name; const char *summary; const char *paper; meso_technique_kind kind;
    unsigned accepts; const meso_technique_option *options; size_t num_options; ...;
} meso_technique_info;
size_t meso_technique_count(void);
const char *meso_technique_isa(void);
const meso_technique_info *meso_technique_get(size_t index);
const meso_technique_info *meso_technique_find(const char *name);
meso_result meso_technique_check_option(meso_context *ctx, const char *technique,
                                        const char *name, double value, const char *where);
typedef struct meso_render_desc {
    const char *technique; int samples; bool wireframe; const meso_option *options;
    int num_options; bool progress; bool fallback; ...;
} meso_render_desc;
uint64_t meso_render_memory_estimate(const meso_render_desc *desc, int width, int height);
typedef struct meso_render_stats {
    double prepare_seconds; double last_frame_seconds; uint64_t triangles; uint64_t fragments;
    size_t memory_bytes; ...;
} meso_render_stats;
typedef struct meso_renderer meso_renderer;
meso_result meso_renderer_create(meso_context *ctx, const meso_scene *scene,
                                 const meso_render_desc *desc, meso_renderer **out_renderer);
meso_result meso_renderer_render(meso_renderer *renderer, meso_framebuffer *fb);
meso_render_stats meso_renderer_get_stats(const meso_renderer *renderer);
const char *meso_renderer_object_technique(const meso_renderer *renderer, int object);
void meso_renderer_destroy(meso_renderer *renderer);

typedef struct meso_compare_desc {
    const meso_image *coverage_a; const meso_image *coverage_b; float background[3]; ...;
} meso_compare_desc;
typedef struct meso_compare_result {
    double psnr; double psnr_covered; double rmse, rmse_covered; double ssim; double max_error;
    double coverage_iou; size_t covered_both, covered_only_a, covered_only_b; ...;
} meso_compare_result;
meso_result meso_image_compare(meso_context *ctx, const meso_image *a, const meso_image *b,
                               const meso_compare_desc *desc, meso_compare_result *out_result);
meso_result meso_image_diff(meso_context *ctx, const meso_image *a, const meso_image *b,
                            float full_scale, meso_image **out_image);

/* Python functions libmeso calls back (progress of bakes, warnings), from any thread: cffi
 * takes the GIL for them. */
extern "Python" bool meso_python_progress(void *user, const char *label, double fraction);
extern "Python" void meso_python_log(void *user, meso_log_level level, const char *message);
"""


def _pkg_config(*args):
    try:
        out = subprocess.run(["pkg-config", *args, "libmeso"], check=True, capture_output=True,
                             text=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return None
    return shlex.split(out)


def library_dirs():
    """(include_dir, library_dir) of the libmeso.so to build against."""
    include_dir = os.environ.get("MESO_INCLUDE_DIR")
    library_dir = os.environ.get("MESO_LIBRARY_DIR")
    if include_dir and library_dir:
        return include_dir, library_dir
    cflags, libs = _pkg_config("--cflags-only-I"), _pkg_config("--libs-only-L")
    if cflags is not None and libs is not None:
        includes = [flag[2:] for flag in cflags if flag.startswith("-I")]
        libdirs = [flag[2:] for flag in libs if flag.startswith("-L")]
        if includes and libdirs:
            return include_dir or includes[0], library_dir or libdirs[0]
    source = os.path.dirname(HERE)
    return (include_dir or os.path.join(source, "include"),
            library_dir or os.path.join(source, "build"))


def make_builder():
    include_dir, library_dir = library_dirs()
    builder = cffi.FFI()
    builder.cdef(CDEF)
    builder.set_source(
        "meso._meso_cffi", "#include <meso/meso.h>\n",
        include_dirs=[include_dir], library_dirs=[library_dir], libraries=["meso"],
        # found at run time where it was linked: the build tree or the installed prefix
        extra_link_args=["-Wl,-rpath," + os.path.abspath(library_dir)])
    return builder


ffibuilder = make_builder()

if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build-dir", required=True,
                        help="folder that receives meso/_meso_cffi*.so (and the generated C)")
    arguments = parser.parse_args()
    ffibuilder.compile(tmpdir=arguments.build_dir, verbose=False)
