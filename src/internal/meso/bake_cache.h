/* The bake cache (docs/bake-format.md, "The bake cache"; not installed): where the cached
 * bakes (meso_<kind>_bake_cached) keep their files, and the claim that makes concurrent callers
 * bake an entry once. */
#ifndef MESO_BAKE_CACHE_H
#define MESO_BAKE_CACHE_H

#include "meso/bake_file.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- The bake cache (docs/bake-format.md, "The bake cache") -------------------------------
 * Files <dir>/<kind>-<key as 16 hex digits>.mesobake; dir is $MESO_CACHE_DIR, else
 * $XDG_CACHE_HOME/meso, else $HOME/.cache/meso. MESO_CACHE_DIR=off disables the cache. */

/* The cache folder, created when missing, into out_dir (size bytes). Returns MESO_OK,
 * MESO_ERROR_UNSUPPORTED when the cache is disabled or no folder can be found (not logged),
 * MESO_ERROR_IO when it cannot be created (logged). Thread-safe. */
meso_result meso_bake_cache_dir(meso_context *ctx, char *out_dir, size_t size);
/* The cache file of (kind, key) into out_path. Same results as meso_bake_cache_dir. */
meso_result meso_bake_cache_path(meso_context *ctx, const char *kind, uint64_t key, char *out_path,
                                 size_t size);
/* The cached bake of (kind, key) made from the source whose hash is source_hash: *out_bake is
 * the loaded file (caller destroys) or NULL when there is none, the cache is disabled, or the
 * entry is unreadable, corrupted, of another kind / kind_version or made from another source
 * (the stored source hash differs: a key collision or a planted file; a warning is logged and
 * the entry will be replaced). Always MESO_OK unless out of memory. Thread-safe. */
meso_result meso_bake_cache_load(meso_context *ctx, const char *kind, uint32_t kind_version,
                                 uint64_t key, uint64_t source_hash, meso_bake_file **out_bake);
/* Store a bake under (bake->kind, key), atomically. MESO_OK also when the cache is disabled. */
meso_result meso_bake_cache_save(meso_context *ctx, const meso_bake_file *bake, uint64_t key);

/* An exclusive claim on one cache entry, across threads, processes and machines sharing the
 * folder: the cached bakes (meso_vdm_bake_cached, ...) hold it from looking the entry up to
 * storing it, so of several processes needing one missing entry at once one bakes and the
 * others wait and then load it. It is an advisory lock (flock) on "<entry>.lock", removed by
 * its holder on release; where locks are not available (some NFS set-ups) the claim is empty
 * and concurrent bakes of one entry each store the same bytes atomically, which is safe too. */
typedef struct meso_bake_cache_claim {
    int fd; /* -1: no claim (cache off, or locks unavailable) */
    char path[1200];
} meso_bake_cache_claim;
/* Wait for and take the claim on (kind, key). Never fails: at worst the claim is empty. */
void meso_bake_cache_claim_entry(meso_context *ctx, const char *kind, uint64_t key,
                                 meso_bake_cache_claim *out_claim);
/* Give the claim up (its lock file removed); an empty claim is fine. */
void meso_bake_cache_release(meso_bake_cache_claim *claim);

#ifdef __cplusplus
}
#endif
#endif
