/* The technique registry: every entry of techniques/technique_list.h, then `reference`. */
#include <stdio.h>
#include <string.h>

#include "reference_internal.h"

/* The reference tracer is a back end (reference.c), not a fragment function: its entry only
 * names it and says what it accepts. */
static const meso_technique technique_reference = {
    .info = {.name = "reference",
             .summary = "ray traces the true micro-geometry (ground truth)",
             .paper = "ground truth: the displaced / mapped mesostructure as real geometry",
             .kind = MESO_TECHNIQUE_REFERENCE,
             .accepts = MESO_TECHNIQUE_ACCEPTS_NONE | MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD |
                        MESO_TECHNIQUE_ACCEPTS_SOLID,
             .options = meso_reference_options,
             .num_options = MESO_REFERENCE_NUM_OPTIONS},
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

void meso_technique_list_names(char *buffer, size_t size) {
    size_t used = 0;
    buffer[0] = 0;
    for (size_t i = 0; i < NUM_TECHNIQUES; i++) {
        int w =
            snprintf(buffer + used, size - used, "%s%s", i ? ", " : "", techniques[i]->info.name);
        if (w < 0 || (size_t)w >= size - used) return;
        used += (size_t)w;
    }
}
