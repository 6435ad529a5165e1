/* The technique registry: every entry of techniques/technique_list.h, then `reference`. */
#include <stdio.h>
#include <string.h>

#include "render_internal.h"

#define MESO_TECHNIQUE(name) extern const meso_technique meso_technique_##name;
#include "technique_list.h"
#undef MESO_TECHNIQUE

/* The reference tracer is a back end (reference.c), not a fragment function: its entry only
 * names it and says what it accepts. */
static const meso_technique technique_reference = {
    .info = {.name = "reference",
             .summary = "ray traces the true micro-geometry (ground truth)",
             .paper = "ground truth: the displaced / mapped mesostructure as real geometry",
             .kind = MESO_TECHNIQUE_REFERENCE,
             .accepts = MESO_TECHNIQUE_ACCEPTS_NONE | MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD |
                        MESO_TECHNIQUE_ACCEPTS_SOLID},
};

static const meso_technique *const techniques[] = {
#define MESO_TECHNIQUE(name) &meso_technique_##name,
#include "technique_list.h"
#undef MESO_TECHNIQUE
    &technique_reference,
};
#define NUM_TECHNIQUES (sizeof(techniques) / sizeof(techniques[0]))

size_t meso_technique_count(void) { return NUM_TECHNIQUES; }

const meso_technique_info *meso_technique_get(size_t index) {
    return index < NUM_TECHNIQUES ? &techniques[index]->info : NULL;
}

const meso_technique *meso_technique_lookup(const char *name) {
    if (!name) return NULL;
    for (size_t i = 0; i < NUM_TECHNIQUES; i++) {
        if (strcmp(techniques[i]->info.name, name) == 0) return techniques[i];
    }
    return NULL;
}

const meso_technique_info *meso_technique_find(const char *name) {
    const meso_technique *t = meso_technique_lookup(name);
    return t ? &t->info : NULL;
}

meso_result meso_technique_check_options(meso_context *ctx, const meso_object *object,
                                         const char *technique, const char *const *known) {
    for (int i = 0; i < object->num_options; i++) {
        const char *name = object->options[i].name;
        bool found = false;
        for (size_t k = 0; known && known[k] && !found; k++) found = strcmp(known[k], name) == 0;
        if (found) continue;
        char list[512] = "";
        size_t used = 0;
        for (size_t k = 0; known && known[k]; k++) {
            int w = snprintf(list + used, sizeof(list) - used, "%s%s", k ? ", " : "", known[k]);
            if (w < 0 || (size_t)w >= sizeof(list) - used) break;
            used += (size_t)w;
        }
        return meso_log_error(ctx, MESO_ERROR_INVALID_ARGUMENT,
                              "%s: technique_options.%s: unknown option of technique '%s' (%s%s)",
                              object->name, name, technique, used ? "known: " : "it has none",
                              list);
    }
    return MESO_OK;
}
