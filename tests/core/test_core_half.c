/* IEEE binary16 conversions in plain integer arithmetic (meso/math.h): the VDM weights are
 * stored as halves, and every compiler must give the same bits. Defect: they were converted
 * with _Float16, which clang 14 does not have on x86-64, so the render module did not build
 * with clang and the float-cast-overflow job could not run. Checked against the CPU's own
 * conversion (F16C) where it has one, and GCC's _Float16 where the compiler has it. */
#include <string.h>

#include "test_util.h"

#if defined(__x86_64__)
#include <cpuid.h>
#include <immintrin.h>
#define HAVE_F16C_TARGET 1
/* CPUID leaf 1, ECX bit 29 (clang 14's __builtin_cpu_supports does not know "f16c") */
static bool cpu_has_f16c(void) {
    unsigned a, b, c, d;
    return __get_cpuid(1, &a, &b, &c, &d) && (c >> 29) & 1u;
}
__attribute__((target("f16c"))) static uint16_t f16c_from_float(float value) {
    return (uint16_t)_cvtss_sh(value, _MM_FROUND_TO_NEAREST_INT);
}
__attribute__((target("f16c"))) static float f16c_to_float(uint16_t half) {
    return _cvtsh_ss(half);
}
#else
#define HAVE_F16C_TARGET 0
#endif

static uint32_t float_bits(float value) {
    uint32_t bits;
    memcpy(&bits, &value, sizeof(bits));
    return bits;
}
static float bits_float(uint32_t bits) {
    float value;
    memcpy(&value, &bits, sizeof(value));
    return value;
}

static void test_known_values_round_to_nearest_even(void **state) {
    (void)state;
    assert_int_equal(meso_half_from_float(1.0f), 0x3c00);
    assert_int_equal(meso_half_from_float(-2.0f), 0xc000);
    assert_int_equal(meso_half_from_float(65504.0f), 0x7bff);   /* largest half */
    assert_int_equal(meso_half_from_float(65519.996f), 0x7bff); /* below the tie */
    assert_int_equal(meso_half_from_float(65520.0f), 0x7c00);   /* tie: to even = Inf */
    assert_int_equal(meso_half_from_float(1e30f), 0x7c00);
    assert_int_equal(meso_half_from_float(-INFINITY), 0xfc00);
    assert_int_equal(meso_half_from_float(0x1p-24f), 0x0001); /* smallest subnormal */
    assert_int_equal(meso_half_from_float(0x1p-25f), 0x0000); /* tie: to even = 0 */
    assert_int_equal(meso_half_from_float(0x1.8p-25f), 0x0001);
    assert_int_equal(meso_half_from_float(0x1.8p-24f), 0x0002);      /* tie 1.5: to even 2 */
    assert_int_equal(meso_half_from_float(0x1p-14f), 0x0400);        /* smallest normal */
    assert_int_equal(meso_half_from_float(1.0f + 0x1p-11f), 0x3c00); /* tie: to even */
    assert_int_equal(meso_half_from_float(1.0f + 0x1.8p-11f), 0x3c01);
    assert_true(isnan(meso_half_to_float(meso_half_from_float(NAN))));
    assert_true(meso_half_to_float(0x0001) == 0x1p-24f);
    assert_true(meso_half_to_float(0x7bff) == 65504.0f);
    assert_true(meso_half_to_float(0xfc00) == -INFINITY);
}

/* Every half survives half -> float -> half, and matches the CPU's conversion. */
static void test_every_half_round_trips_and_matches_the_cpu(void **state) {
    (void)state;
#if HAVE_F16C_TARGET
    bool cpu = cpu_has_f16c();
#endif
    for (uint32_t h = 0; h < 65536; h++) {
        float value = meso_half_to_float((uint16_t)h);
        bool nan = ((h >> 10) & 0x1f) == 0x1f && (h & 0x3ff);
        if (nan) {
            assert_true(isnan(value));
            continue;
        }
        if (meso_half_from_float(value) != h) fail_msg("half 0x%04x does not round-trip", h);
#if HAVE_F16C_TARGET
        if (cpu && float_bits(f16c_to_float((uint16_t)h)) != float_bits(value))
            fail_msg("half 0x%04x: %a, F16C says %a", h, value, f16c_to_float((uint16_t)h));
#endif
    }
}

/* Floats of every exponent (a prime stride through all bit patterns, plus the neighbours of
 * every rounding tie) give the CPU's and the compiler's bits. */
static void check_float(uint32_t bits) {
    float value = bits_float(bits);
    uint16_t ours = meso_half_from_float(value);
    if (isnan(value)) {
        assert_true(isnan(meso_half_to_float(ours)));
        return;
    }
#if HAVE_F16C_TARGET
    static int cpu = -1;
    if (cpu < 0) cpu = cpu_has_f16c();
    if (cpu && f16c_from_float(value) != ours)
        fail_msg("%a: 0x%04x, F16C says 0x%04x", value, ours, f16c_from_float(value));
#endif
#ifdef __FLT16_MANT_DIG__
    _Float16 compiler = (_Float16)value;
    uint16_t compiler_bits;
    memcpy(&compiler_bits, &compiler, sizeof(compiler_bits));
    if (compiler_bits != ours)
        fail_msg("%a: 0x%04x, _Float16 says 0x%04x", value, ours, compiler_bits);
#endif
}

static void test_floats_convert_as_the_cpu_and_compiler_do(void **state) {
    (void)state;
    for (uint64_t bits = 0; bits <= 0xffffffffu; bits += 4099) check_float((uint32_t)bits);
    /* the ties between two halves and their float neighbours, for every half */
    for (uint32_t h = 0; h < 0x7c00; h++) {
        uint32_t tie = float_bits(
            (meso_half_to_float((uint16_t)h) + meso_half_to_float((uint16_t)(h + 1))) * 0.5f);
        for (uint32_t d = 0; d < 3; d++) {
            check_float(tie - 1 + d);
            check_float((tie - 1 + d) | 0x80000000u);
        }
    }
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_known_values_round_to_nearest_even),
        cmocka_unit_test(test_every_half_round_trips_and_matches_the_cpu),
        cmocka_unit_test(test_floats_convert_as_the_cpu_and_compiler_do),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
