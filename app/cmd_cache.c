/* meso cache list|clear|size: the bake cache (docs/bake-format.md, "The bake cache"). Only
 * files meso writes there are listed or removed: <kind>-<key>.mesobake, the temporary files
 * of an interrupted write (<name>.mesobake.tmpXXXXXX) and the lock files of claims
 * (<name>.mesobake.lock); anything else in the folder is left. */
#include "app.h"

#include <dirent.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include "meso/bake_cache.h"
#include "meso/runtime.h"

static const app_command_help cache_help = {
    .name = "cache",
    .usage = "list|size|clear [options]",
    .summary =
        "Show or empty the bake cache: $MESO_CACHE_DIR, else $XDG_CACHE_HOME/meso, else\n"
        "~/.cache/meso (MESO_CACHE_DIR=off disables it). `list` prints each bake (name, size,\n"
        "date) on stdout, `size` the number of bakes and their total size, `clear` removes them.\n"
        "Bakes are made again when next needed.",
    .examples = "  meso cache list\n  meso cache size\n  meso cache clear\n",
};

typedef struct cache_entry {
    char name[256];
    long long bytes;
    time_t modified;
} cache_entry;

/* A name meso writes into the cache. */
static bool is_cache_file(const char *name) {
    const char *suffix = strstr(name, ".mesobake");
    if (!suffix || suffix == name) return false;
    return suffix[9] == 0 || strncmp(suffix + 9, ".tmp", 4) == 0 ||
           strcmp(suffix + 9, ".lock") == 0; /* a claim's lock file (bake_file.h) */
}

static int compare_names(const void *a, const void *b) {
    return strcmp(((const cache_entry *)a)->name, ((const cache_entry *)b)->name);
}

/* The cache's files, sorted by name, into *out (caller frees). */
static meso_result read_cache(meso_context *ctx, const char *dir, cache_entry **out,
                              size_t *out_count) {
    *out = NULL;
    *out_count = 0;
    DIR *d = opendir(dir);
    if (!d)
        return meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot open the bake cache: %s", dir,
                              strerror(errno));
    size_t count = 0, capacity = 0;
    cache_entry *entries = NULL;
    meso_result result = MESO_OK;
    for (struct dirent *e = readdir(d); e; e = readdir(d)) {
        if (!is_cache_file(e->d_name) || strlen(e->d_name) >= sizeof entries->name) continue;
        char path[4096];
        struct stat st;
        if (!app_path_join(path, sizeof path, dir, e->d_name) || stat(path, &st) != 0 ||
            !S_ISREG(st.st_mode))
            continue;
        if (count == capacity) {
            size_t grown = capacity ? 2 * capacity : 64;
            cache_entry *bigger = realloc(entries, grown * sizeof *entries);
            if (!bigger) {
                result = meso_log_error(ctx, MESO_ERROR_OUT_OF_MEMORY, "cache: out of memory");
                break;
            }
            entries = bigger;
            capacity = grown;
        }
        snprintf(entries[count].name, sizeof entries[count].name, "%s", e->d_name);
        entries[count].bytes = (long long)st.st_size;
        entries[count].modified = st.st_mtime;
        count++;
    }
    closedir(d);
    if (result != MESO_OK) {
        free(entries);
        return result;
    }
    if (count > 1) qsort(entries, count, sizeof *entries, compare_names);
    *out = entries;
    *out_count = count;
    return MESO_OK;
}

static double mebibytes(long long bytes) { return (double)bytes / (1024.0 * 1024.0); }

static meso_result run(meso_context *ctx, const char *action, const char *dir, bool quiet) {
    cache_entry *entries = NULL;
    size_t count = 0;
    meso_result result = read_cache(ctx, dir, &entries, &count);
    if (result != MESO_OK) return result;
    long long total = 0;
    for (size_t i = 0; i < count; i++) total += entries[i].bytes;
    if (strcmp(action, "list") == 0) {
        for (size_t i = 0; i < count; i++) {
            char date[32];
            strftime(date, sizeof date, "%Y-%m-%d %H:%M", localtime(&entries[i].modified));
            printf("%-48s %10.1f MiB  %s\n", entries[i].name, mebibytes(entries[i].bytes), date);
        }
        if (!quiet)
            fprintf(stderr, "meso: cache: %zu bakes, %.1f MiB in %s\n", count, mebibytes(total),
                    dir);
    } else if (strcmp(action, "size") == 0) {
        printf("%zu bakes, %.1f MiB (%lld bytes) in %s\n", count, mebibytes(total), total, dir);
    } else { /* clear */
        size_t removed = 0;
        long long freed = 0;
        for (size_t i = 0; i < count && result == MESO_OK; i++) {
            char path[4096];
            if (!app_path_join(path, sizeof path, dir, entries[i].name)) continue;
            if (remove(path) == 0) {
                removed++;
                freed += entries[i].bytes;
            } else if (errno != ENOENT) {
                result = meso_log_error(ctx, MESO_ERROR_IO, "%s: cannot remove: %s", path,
                                        strerror(errno));
            }
        }
        if (!quiet)
            fprintf(stderr, "meso: cache: removed %zu bakes, %.1f MiB from %s\n", removed,
                    mebibytes(freed), dir);
    }
    free(entries);
    return result;
}

int meso_cmd_cache(int argc, char **argv) {
    app_globals globals;
    const char *positionals[1];
    int num_positionals = 0;
    int status = app_parse_options(&cache_help, NULL, 0, argc, argv, &globals, positionals, 1,
                                   &num_positionals);
    if (status >= 0) return status;
    if (num_positionals < 1)
        return app_usage_error("cache", "missing the action: list, size or clear");
    const char *action = positionals[0];
    if (strcmp(action, "list") != 0 && strcmp(action, "size") != 0 && strcmp(action, "clear") != 0)
        return app_usage_error("cache", "unknown action '%s' (list, size or clear)", action);
    meso_context *ctx = app_context_create(&globals);
    if (!ctx) return APP_EXIT_FAILURE;
    char dir[1024];
    meso_result result = meso_bake_cache_dir(ctx, dir, sizeof dir);
    if (result == MESO_ERROR_UNSUPPORTED) { /* off, or no folder: nothing is cached */
        if (strcmp(action, "size") == 0) printf("0 bakes: the bake cache is off\n");
        if (!globals.quiet)
            fprintf(stderr, "meso: note: cache: the bake cache is off (MESO_CACHE_DIR=off or no "
                            "HOME)\n");
        meso_context_destroy(ctx);
        return APP_EXIT_OK;
    }
    if (result == MESO_OK) result = run(ctx, action, dir, globals.quiet);
    status = result == MESO_OK ? APP_EXIT_OK : app_fail(ctx, result);
    meso_context_destroy(ctx);
    return status;
}
