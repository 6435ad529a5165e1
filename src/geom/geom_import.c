/* Mesh import through assimp's C API: OBJ, PLY, glTF and whatever else assimp reads.
 *
 * Every triangle mesh of the file is placed by its node's accumulated transform and joined
 * into one meso_mesh. UV channel 0 is kept as assimp gives it (OpenGL convention, docs/design.md:
 * nothing is flipped). The result goes through meso_mesh_validate, so errors and the
 * degenerate-triangle warning name the file.
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "geom_internal.h"
#include "meso/runtime.h"

/* assimp's C API keeps its last error in one global string (and its loggers are global), so
 * imports are serialised to keep meso_mesh_load thread-safe. */
static pthread_mutex_t import_lock = PTHREAD_MUTEX_INITIALIZER;

/* Nodes visited per file at most: a scene graph is a tree, this only stops a corrupt one. */
#define MAX_NODES (1u << 22)

/* ---- The files assimp may open --------------------------------------------------------- */

/* assimp opens files through these callbacks only: the mesh file itself, and for a glTF the
 * buffers its screening allowed (files beside it). Every other open fails: an OBJ's material
 * libraries are read by meso's own MTL reader (geom_mtl.c), never by assimp's parser, which
 * crashed on malformed ones. Files are opened non-blocking and must be regular (a FIFO would
 * block the import). */
typedef struct import_files {
    const char *path; /* the mesh file */
    bool others_allowed;
} import_files;

static FILE *file_of(struct aiFile *f) { return (FILE *)(void *)f->UserData; }

static size_t file_read(struct aiFile *f, char *buffer, size_t size, size_t count) {
    return size && count ? fread(buffer, size, count, file_of(f)) : 0;
}

static size_t file_write(struct aiFile *f, const char *buffer, size_t size, size_t count) {
    (void)f, (void)buffer, (void)size, (void)count;
    return 0;
}

static size_t file_tell(struct aiFile *f) {
    off_t at = ftello(file_of(f));
    return at < 0 ? 0 : (size_t)at;
}

static size_t file_size(struct aiFile *f) {
    struct stat st;
    return fstat(fileno(file_of(f)), &st) == 0 ? (size_t)st.st_size : 0;
}

static enum aiReturn file_seek(struct aiFile *f, size_t offset, enum aiOrigin origin) {
    int whence = origin == aiOrigin_SET ? SEEK_SET : origin == aiOrigin_CUR ? SEEK_CUR : SEEK_END;
    /* assimp passes a negative relative offset as its size_t image */
    off_t signed_offset = origin == aiOrigin_SET ? (off_t)offset : (off_t)(ptrdiff_t)offset;
    return fseeko(file_of(f), signed_offset, whence) == 0 ? aiReturn_SUCCESS : aiReturn_FAILURE;
}

static void file_flush(struct aiFile *f) { (void)f; }

static struct aiFile *file_open(struct aiFileIO *io, const char *path, const char *mode) {
    const import_files *rules = (const import_files *)(void *)io->UserData;
    if (!path || strchr(mode, 'w') || strchr(mode, 'a') ||
        (strcmp(path, rules->path) != 0 && !rules->others_allowed))
        return NULL;
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return NULL;
    struct stat st;
    FILE *file = NULL;
    if (fstat(fd, &st) == 0 && S_ISREG(st.st_mode)) {
        int flags = fcntl(fd, F_GETFL);
        if (flags >= 0) fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
        file = fdopen(fd, "rb");
    }
    struct aiFile *f = file ? malloc(sizeof(*f)) : NULL;
    if (!f) {
        if (file)
            fclose(file);
        else
            close(fd);
        return NULL;
    }
    *f = (struct aiFile){file_read,
                         file_write,
                         file_tell,
                         file_size,
                         file_seek,
                         file_flush,
                         (aiUserData)(void *)file};
    return f;
}

static void file_close(struct aiFileIO *io, struct aiFile *f) {
    (void)io;
    if (!f) return;
    fclose(file_of(f));
    free(f);
}

typedef struct mesh_instance {
    const struct aiMesh *mesh;
    meso_mat4 transform;
} mesh_instance;

typedef struct import_state {
    meso_context *ctx;
    const char *path;
    mesh_instance *instances;
    size_t num_instances, capacity;
} import_state;

static meso_mat4 from_assimp(const struct aiMatrix4x4 *m) {
    /* aiMatrix4x4 is row-major (a1 a2 a3 a4 is the first row) for column vectors; meso_mat4 is
     * column-major. */
    return (meso_mat4){{m->a1, m->b1, m->c1, m->d1, m->a2, m->b2, m->c2, m->d2, m->a3, m->b3, m->c3,
                        m->d3, m->a4, m->b4, m->c4, m->d4}};
}

static bool is_triangle_mesh(const struct aiMesh *mesh) {
    return mesh && (mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) && mesh->mVertices;
}

static meso_result add_instance(import_state *s, const struct aiMesh *mesh, meso_mat4 transform) {
    if (s->num_instances == s->capacity) {
        size_t capacity = s->capacity ? 2 * s->capacity : 16;
        mesh_instance *grown = realloc(s->instances, capacity * sizeof(*grown));
        if (!grown)
            return meso_log_error(s->ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", s->path);
        s->instances = grown;
        s->capacity = capacity;
    }
    s->instances[s->num_instances++] = (mesh_instance){mesh, transform};
    return MESO_OK;
}

/* Every (mesh, accumulated transform) of the node tree, depth first, with an explicit stack. */
static meso_result collect_instances(import_state *s, const struct aiScene *scene) {
    typedef struct frame {
        const struct aiNode *node;
        meso_mat4 parent;
    } frame;
    size_t capacity = 64, depth = 0, visited = 0;
    frame *stack = malloc(capacity * sizeof(frame));
    if (!stack)
        return meso_log_error(s->ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory", s->path);
    meso_result r = MESO_OK;
    stack[depth++] = (frame){scene->mRootNode, meso_mat4_identity()};
    while (depth > 0 && r == MESO_OK) {
        frame f = stack[--depth];
        if (!f.node) continue;
        if (++visited > MAX_NODES) {
            r = meso_log_error(s->ctx, MESO_ERROR_LIMIT, "%s: more than %u scene nodes", s->path,
                               MAX_NODES);
            break;
        }
        meso_mat4 world = meso_mat4_mul(f.parent, from_assimp(&f.node->mTransformation));
        for (unsigned k = 0; k < f.node->mNumMeshes && r == MESO_OK; k++) {
            unsigned index = f.node->mMeshes[k];
            if (index >= scene->mNumMeshes) {
                r = meso_log_error(s->ctx, MESO_ERROR_FORMAT, "%s: node refers to mesh %u of %u",
                                   s->path, index, scene->mNumMeshes);
                break;
            }
            if (is_triangle_mesh(scene->mMeshes[index]))
                r = add_instance(s, scene->mMeshes[index], world);
        }
        /* Children pushed in reverse so they are visited in file order. */
        for (unsigned c = f.node->mNumChildren; c-- > 0 && r == MESO_OK;) {
            if (depth == capacity) {
                frame *grown = realloc(stack, 2 * capacity * sizeof(frame));
                if (!grown) {
                    r = meso_log_error(s->ctx, MESO_ERROR_OUT_OF_MEMORY, "%s: out of memory",
                                       s->path);
                    break;
                }
                stack = grown;
                capacity *= 2;
            }
            stack[depth++] = (frame){f.node->mChildren[c], world};
        }
    }
    free(stack);
    return r;
}

static size_t count_triangles(const struct aiMesh *mesh) {
    size_t count = 0;
    for (unsigned f = 0; f < mesh->mNumFaces; f++) count += mesh->mFaces[f].mNumIndices == 3;
    return count;
}

/* Copy the instances into one mesh (counts already checked against the limits). */
static meso_result join_instances(import_state *s, size_t num_vertices, size_t num_triangles,
                                  bool with_uvs, meso_mesh **out_mesh) {
    meso_mesh *mesh = NULL;
    meso_result r = meso_mesh_create(s->ctx, num_vertices, num_triangles, with_uvs, &mesh);
    if (r != MESO_OK) return r;
    size_t vertex = 0, triangle = 0;
    for (size_t i = 0; i < s->num_instances; i++) {
        const struct aiMesh *m = s->instances[i].mesh;
        meso_mat4 transform = s->instances[i].transform;
        meso_mat4 normal_matrix = meso_mat4_normal_matrix(transform);
        const float *a = transform.m;
        float det = a[0] * (a[5] * a[10] - a[9] * a[6]) - a[4] * (a[1] * a[10] - a[9] * a[2]) +
                    a[8] * (a[1] * a[6] - a[5] * a[2]);
        for (unsigned v = 0; v < m->mNumVertices; v++) {
            const struct aiVector3D *p = &m->mVertices[v];
            mesh->positions[vertex + v] =
                meso_mat4_transform_point(transform, meso_vec3_make(p->x, p->y, p->z));
            if (m->mNormals) {
                const struct aiVector3D *n = &m->mNormals[v];
                mesh->normals[vertex + v] = meso_vec3_normalize(
                    meso_mat4_transform_direction(normal_matrix, meso_vec3_make(n->x, n->y, n->z)));
            } /* else zero: meso_mesh_validate rebuilds it from the triangles */
            if (with_uvs && m->mTextureCoords[0])
                mesh->uvs[vertex + v] =
                    meso_vec2_make(m->mTextureCoords[0][v].x, m->mTextureCoords[0][v].y);
        }
        for (unsigned f = 0; f < m->mNumFaces; f++) {
            const struct aiFace *face = &m->mFaces[f];
            if (face->mNumIndices != 3) continue;
            for (int k = 0; k < 3; k++) {
                unsigned index = face->mIndices[k];
                if (index >= m->mNumVertices) {
                    meso_mesh_destroy(mesh);
                    return meso_log_error(s->ctx, MESO_ERROR_FORMAT,
                                          "%s: face %u: vertex index %u is out of range "
                                          "(%u vertices)",
                                          s->path, f, index, m->mNumVertices);
                }
                /* A mirroring node transform reverses the winding; swap to keep it
                 * counter-clockwise from outside. */
                int corner = det < 0.0f && k > 0 ? 3 - k : k;
                mesh->indices[3 * triangle + corner] = (uint32_t)(vertex + index);
            }
            triangle++;
        }
        vertex += m->mNumVertices;
    }
    *out_mesh = mesh;
    return MESO_OK;
}

/* What the post-processing steps need and assimp does not check: every face has corners,
 * and the counts (which post-processing can only shrink: a polygon of n corners becomes n - 2
 * triangles) are within the limits before assimp allocates for them. */
static meso_result check_raw_scene(meso_context *ctx, const char *path,
                                   const struct aiScene *scene) {
    uint64_t num_vertices = 0, num_corners = 0;
    for (unsigned m = 0; m < scene->mNumMeshes; m++) {
        const struct aiMesh *mesh = scene->mMeshes[m];
        if (!mesh) return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: mesh %u is missing", path, m);
        num_vertices += mesh->mNumVertices;
        for (unsigned f = 0; f < mesh->mNumFaces; f++) {
            if (mesh->mFaces[f].mNumIndices == 0)
                return meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: mesh %u: face %u has no corners",
                                      path, m, f);
            num_corners += mesh->mFaces[f].mNumIndices;
        }
    }
    return geom_check_counts(ctx, path, num_vertices, num_corners / 3);
}

void geom_material_ignore(meso_mesh_material *m, const char *what) {
    if (strstr(m->ignored, what)) return; /* said once (two keys may name one kind) */
    size_t used = strlen(m->ignored);
    snprintf(m->ignored + used, sizeof(m->ignored) - used, "%s%s", used ? ", " : "", what);
}

/* A texture's path of `type`, when it names a file: embedded images ("*0") and data URIs are
 * listed as ignored. */
static void read_texture(const struct aiMaterial *material, enum aiTextureType type,
                         const char *what, char *out, meso_mesh_material *m) {
    struct aiString path;
    if (aiGetMaterialTexture(material, type, 0, &path, NULL, NULL, NULL, NULL, NULL, NULL) !=
            aiReturn_SUCCESS ||
        path.length == 0)
        return;
    char ignored[96];
    if (path.data[0] == '*' || strncmp(path.data, "data:", 5) == 0) {
        snprintf(ignored, sizeof ignored, "%s (embedded image)", what);
        geom_material_ignore(m, ignored);
    } else if (path.length >= MESO_MESH_MATERIAL_PATH_MAX) {
        snprintf(ignored, sizeof ignored, "%s (path too long)", what);
        geom_material_ignore(m, ignored);
    } else {
        memcpy(out, path.data, path.length + 1);
    }
}

const char *meso_mesh_material_unused_reason(const char *texture) {
    return texture[0] == '/' || strstr(texture, "..") ? "not beside the mesh file" : NULL;
}

static void note_other_materials(const import_state *s, unsigned index, meso_mesh_material *m) {
    size_t others = 0;
    for (size_t i = 1; i < s->num_instances; i++)
        others += s->instances[i].mesh->mMaterialIndex != index;
    if (others) {
        char text[96];
        snprintf(text, sizeof text, "the materials of %zu other mesh%s", others,
                 others == 1 ? "" : "es");
        geom_material_ignore(m, text);
    }
}

/* The first instance's material; what else the file holds goes to `ignored`. An OBJ's
 * material is read from its MTL by meso (assimp saw only the `usemtl` name). */
static meso_result read_material(meso_context *ctx, const char *path, FILE *obj,
                                 const struct aiScene *scene, const import_state *s,
                                 meso_mesh_material *m) {
    memset(m, 0, sizeof(*m));
    if (s->num_instances == 0 || !scene->mMaterials) return MESO_OK;
    unsigned index = s->instances[0].mesh->mMaterialIndex;
    if (index >= scene->mNumMaterials) return MESO_OK;
    const struct aiMaterial *material = scene->mMaterials[index];
    struct aiString name;
    bool named = aiGetMaterialString(material, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS;
    if (named && strcmp(name.data, AI_DEFAULT_MATERIAL_NAME) == 0)
        return MESO_OK; /* assimp's stand-in for "no material" */
    if (obj) {
        meso_result r = named ? geom_obj_read_material(ctx, path, obj, name.data, m) : MESO_OK;
        if (r == MESO_OK) note_other_materials(s, index, m);
        return r;
    }
    struct aiColor4D color;
    if (aiGetMaterialColor(material, AI_MATKEY_COLOR_DIFFUSE, &color) == aiReturn_SUCCESS &&
        isfinite(color.r) && isfinite(color.g) && isfinite(color.b)) {
        m->has_color = true;
        m->color = (meso_vec3){meso_clampf(color.r, 0.0f, 1.0f), meso_clampf(color.g, 0.0f, 1.0f),
                               meso_clampf(color.b, 0.0f, 1.0f)};
    }
    read_texture(material, aiTextureType_DIFFUSE, "base colour texture", m->color_map, m);
    read_texture(material, aiTextureType_NORMALS, "normal texture", m->normal_map, m);
    static const struct {
        enum aiTextureType type;
        const char *what;
    } unused[] = {{aiTextureType_SPECULAR, "specular texture"},
                  {aiTextureType_EMISSIVE, "emissive texture"},
                  {aiTextureType_HEIGHT, "bump/height texture"},
                  {aiTextureType_OPACITY, "opacity texture"},
                  {aiTextureType_METALNESS, "metallic texture"},
                  {aiTextureType_DIFFUSE_ROUGHNESS, "roughness texture"},
                  {aiTextureType_AMBIENT_OCCLUSION, "occlusion texture"},
                  {aiTextureType_LIGHTMAP, "occlusion texture"}, /* glTF's, in assimp 5.2 */
                  {aiTextureType_UNKNOWN, "metallic-roughness texture"}};
    for (size_t u = 0; u < sizeof(unused) / sizeof(unused[0]); u++)
        if (aiGetMaterialTextureCount(material, unused[u].type) > 0)
            geom_material_ignore(m, unused[u].what);
    note_other_materials(s, index, m);
    return MESO_OK;
}

void geom_import_reason(const char *message, char *out, size_t out_size) {
    if (!message || !message[0]) message = "unknown format";
    size_t length = strcspn(message, "\r\n");
    bool cut = message[length + strspn(message + length, " \t\r\n")] != 0 || length + 1 > out_size;
    if (cut && out_size > 4) {
        size_t keep = length + 4 < out_size ? length : out_size - 5;
        snprintf(out, out_size, "%.*s ...", (int)keep, message);
    } else {
        snprintf(out, out_size, "%.*s", (int)length, message);
    }
}

meso_result meso_mesh_load(meso_context *ctx, const char *path, meso_mesh **out_mesh) {
    return meso_mesh_load_with_material(ctx, path, out_mesh, NULL);
}

meso_result meso_mesh_load_with_material(meso_context *ctx, const char *path, meso_mesh **out_mesh,
                                         meso_mesh_material *out_material) {
    *out_mesh = NULL;
    if (out_material) memset(out_material, 0, sizeof(*out_material));
    FILE *probe = NULL; /* a regular file only: assimp would block on a FIFO */
    meso_result opened = meso_file_open_read(ctx, path, &probe);
    if (opened != MESO_OK) return opened;
    geom_mesh_kind kind = GEOM_MESH_OTHER;
    meso_result r = geom_screen_mesh_file(ctx, path, probe, &kind);
    if (r != MESO_OK || kind != GEOM_MESH_OBJ || !out_material) {
        fclose(probe);
        probe = NULL;
    }
    if (r != MESO_OK) return r;
    import_files rules = {path, kind == GEOM_MESH_GLTF};
    struct aiFileIO io = {file_open, file_close, (aiUserData)(void *)&rules};

    import_state s = {ctx, path, NULL, 0, 0};
    meso_mesh *mesh = NULL;
    pthread_mutex_lock(&import_lock);
    /* Two phases. The file is read and validated alone, checked here, and only then
     * post-processed: assimp 5.2 aborts (ai_assert) in Triangulate on a face with no indices,
     * which ValidateDataStructure lets through, and without ValidateDataStructure a face index
     * past the vertex count crashes JoinIdenticalVertices (both found by mutating test
     * files). */
    const struct aiScene *scene = aiImportFileEx(path, aiProcess_ValidateDataStructure, &io);
    if (scene) {
        r = check_raw_scene(ctx, path, scene);
        if (r != MESO_OK) {
            aiReleaseImport(scene);
            pthread_mutex_unlock(&import_lock);
            if (probe) fclose(probe);
            return r;
        }
        /* On failure this releases the scene itself. */
        scene =
            aiApplyPostProcessing(scene, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                             aiProcess_GenSmoothNormals | aiProcess_SortByPType);
    }
    if (!scene) {
        char reason[256];
        geom_import_reason(aiGetErrorString(), reason, sizeof reason);
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: cannot read: %s", path, reason);
        pthread_mutex_unlock(&import_lock);
        if (probe) fclose(probe);
        return r;
    }
    pthread_mutex_unlock(&import_lock);

    if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->mRootNode) {
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: incomplete scene", path);
        goto fail;
    }
    r = collect_instances(&s, scene);
    if (r != MESO_OK) goto fail;

    uint64_t num_vertices = 0, num_triangles = 0;
    size_t with_uvs = 0;
    for (size_t i = 0; i < s.num_instances; i++) {
        num_vertices += s.instances[i].mesh->mNumVertices;
        num_triangles += count_triangles(s.instances[i].mesh);
        with_uvs += s.instances[i].mesh->mTextureCoords[0] != NULL;
    }
    if (num_triangles == 0) {
        r = meso_log_error(ctx, MESO_ERROR_FORMAT, "%s: has no triangles", path);
        goto fail;
    }
    r = geom_check_counts(ctx, path, num_vertices, num_triangles);
    if (r != MESO_OK) goto fail;
    if (with_uvs && with_uvs < s.num_instances)
        meso_log_warning(ctx, "%s: %zu of %zu meshes have no texture coordinates; they get (0, 0)",
                         path, s.num_instances - with_uvs, s.num_instances);
    r = join_instances(&s, (size_t)num_vertices, (size_t)num_triangles, with_uvs > 0, &mesh);
    if (r != MESO_OK) goto fail;
    r = meso_mesh_validate(ctx, mesh, path, false);
    if (r != MESO_OK) goto fail;
    if (out_material) r = read_material(ctx, path, probe, scene, &s, out_material);
    if (r != MESO_OK) goto fail;
    *out_mesh = mesh;
    mesh = NULL;
fail:
    if (probe) fclose(probe);
    meso_mesh_destroy(mesh);
    free(s.instances);
    pthread_mutex_lock(&import_lock);
    aiReleaseImport(scene);
    pthread_mutex_unlock(&import_lock);
    return r;
}
