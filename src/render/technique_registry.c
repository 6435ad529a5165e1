/* The technique registry: every entry of techniques/technique_list.h, then `reference`. A
 * portable x86-64 build also holds each technique compiled for AVX2 + FMA + F16C
 * (meso_technique_<name>_avx2, CMakeLists.txt), handed out when the CPU has them. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if MESO_HAS_AVX2_TECHNIQUES
#include <cpuid.h>
#endif

#include "reference_internal.h"

/* The reference tracer is a back end (reference.c), not a fragment function: its entry only
 * names it and says what it accepts. */
static const meso_technique technique_reference = {
    .info = {.name = "reference",
             .summary = "ray traces the true micro-geometry (ground truth)",
             .paper = "ground truth: the displaced / mapped mesostructure as real geometry",
             .kind = MESO_TECHNIQUE_REFERENCE,
             .accepts = MESO_TECHNIQUE_ACCEPTS_NONE | MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD |
                        MESO_TECHNIQUE_ACCEPTS_SOLID | MESO_TECHNIQUE_ACCEPTS_MODEL_SOLID,
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

#if MESO_HAS_AVX2_TECHNIQUES
#define MESO_TECHNIQUE(name) extern const meso_technique meso_technique_##name##_avx2;
#include "technique_list.h"
#undef MESO_TECHNIQUE
static const meso_technique *const techniques_avx2[] = {
#define MESO_TECHNIQUE(name) &meso_technique_##name##_avx2,
#include "technique_list.h"
#undef MESO_TECHNIQUE
    &technique_reference,
};

/* AVX2 and FMA (which __builtin_cpu_supports checks with the OS's saving of AVX state), and
 * F16C: CPUID leaf 1, ECX bit 29 (clang 14's builtin does not know "f16c"). */
static bool cpu_has_avx2_fma_f16c(void) {
    unsigned a, b, c, d;
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
           __get_cpuid(1, &a, &b, &c, &d) && (c >> 29) & 1u;
}
#endif

/* The table of the instruction set in use: MESO_ISA=baseline forces the portable code (to
 * compare the two: both draw the same bits), otherwise the AVX2 copy where the CPU runs it. */
static const meso_technique *const *technique_table(void) {
#if MESO_HAS_AVX2_TECHNIQUES
    const char *isa = getenv("MESO_ISA");
    if (!(isa && strcmp(isa, "baseline") == 0) && cpu_has_avx2_fma_f16c()) return techniques_avx2;
#endif
    return techniques;
}

const char *meso_technique_isa(void) {
#if MESO_HAS_AVX2_TECHNIQUES
    if (technique_table() == techniques_avx2) return "avx2";
#endif
    return MESO_BUILD_NATIVE ? "native" : "baseline";
}

size_t meso_technique_count(void) { return NUM_TECHNIQUES; }

const meso_technique_info *meso_technique_get(size_t index) {
    return index < NUM_TECHNIQUES ? &technique_table()[index]->info : NULL;
}

const meso_technique *meso_technique_lookup(const char *name) {
    if (!name) return NULL;
    const meso_technique *const *table = technique_table();
    for (size_t i = 0; i < NUM_TECHNIQUES; i++) {
        if (strcmp(table[i]->info.name, name) == 0) return table[i];
    }
    return NULL;
}

const meso_technique_info *meso_technique_find(const char *name) {
    const meso_technique *t = meso_technique_lookup(name);
    return t ? &t->info : NULL;
}

unsigned meso_mesostructure_accepts_bit(const meso_mesostructure *m) {
    switch (m->kind) {
    case MESO_MESOSTRUCTURE_HEIGHT_FIELD:
        return MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD;
    case MESO_MESOSTRUCTURE_SOLID:
        return m->solid && !meso_solid_is_periodic(m->solid) ? MESO_TECHNIQUE_ACCEPTS_MODEL_SOLID
                                                             : MESO_TECHNIQUE_ACCEPTS_SOLID;
    default:
        return MESO_TECHNIQUE_ACCEPTS_NONE;
    }
}

const char *meso_mesostructure_accepts_name(unsigned accepts_bit) {
    switch (accepts_bit) {
    case MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD:
        return "height field";
    case MESO_TECHNIQUE_ACCEPTS_SOLID:
        return "solid";
    case MESO_TECHNIQUE_ACCEPTS_MODEL_SOLID:
        return "model's solid";
    default:
        return "none";
    }
}

bool meso_technique_accepts(const meso_technique_info *technique, const meso_mesostructure *m) {
    return (technique->accepts & meso_mesostructure_accepts_bit(m)) != 0;
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
