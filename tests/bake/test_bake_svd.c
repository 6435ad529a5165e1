/* The streamed SVD of tall tables (bake_svd.c): a matrix with known singular values, built
 * from orthogonal Walsh patterns, spread over several blocks of rows. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_internal.h"
#include "test_util.h"

#define ROWS 20000 /* more than two of the SVD's blocks, and not a multiple of one */
#define COLUMNS 16

static const double singular[3] = {50.0, 10.0, 2.0};

/* Walsh pattern k (k = 0, 1, 2) of index i over n entries: orthogonal when n is a multiple of
 * 4, each of norm sqrt(n). */
static double walsh(int k, size_t i) {
    if (k == 0) return 1.0;
    return ((i >> (k - 1)) & 1) ? -1.0 : 1.0;
}

/* A = sum_k s_k u_k v_k^T with u_k = walsh_k / sqrt(ROWS), v_k = walsh_k / sqrt(COLUMNS). */
static double entry(size_t row, int column) {
    double a = 0.0;
    for (int k = 0; k < 3; k++)
        a += singular[k] * walsh(k, row) / sqrt(ROWS) * walsh(k, (size_t)column) / sqrt(COLUMNS);
    return a;
}

static void fill(void *user, size_t first, size_t count, float *out) {
    (void)user;
    for (size_t r = 0; r < count; r++)
        for (int c = 0; c < COLUMNS; c++) out[r * COLUMNS + c] = (float)entry(first + r, c);
}

typedef struct svd_result {
    float singular[COLUMNS], vectors[COLUMNS * COLUMNS];
    float *weights;
} svd_result;

static void run_svd(int threads, bool keep_table, svd_result *out) {
    meso_context *ctx = test_context(threads);
    meso_bake_rows source = {.rows = ROWS, .columns = COLUMNS, .fill = fill};
    float *table = keep_table ? malloc(sizeof(float) * ROWS * COLUMNS) : NULL;
    out->weights = malloc(sizeof(float) * ROWS * 3);
    assert_int_equal(meso_bake_svd_streamed(ctx, "test", &source, 3, out->singular, out->vectors,
                                            out->weights, table),
                     MESO_OK);
    if (table) {
        assert_true(table[5 * COLUMNS + 3] == (float)entry(5, 3)); /* the raw table, as filled */
        assert_true(table[(ROWS - 1) * COLUMNS + 7] == (float)entry(ROWS - 1, 7));
    }
    free(table);
    meso_context_destroy(ctx);
}

static void test_svd_streamed_finds_the_singular_values_and_reconstructs(void **state) {
    svd_result r;
    run_svd(2, false, &r);
    for (int k = 0; k < 3; k++) assert_true(fabs(r.singular[k] - singular[k]) < 1e-4);
    for (int k = 3; k < COLUMNS; k++) assert_true(r.singular[k] < 1e-3f);
    /* W E^T is A again (signs of U and E cancel) */
    double worst = 0.0;
    for (size_t row = 0; row < ROWS; row += 7)
        for (int c = 0; c < COLUMNS; c++) {
            double sum = 0.0;
            for (int k = 0; k < 3; k++)
                sum += (double)r.weights[row * 3 + k] * r.vectors[c * COLUMNS + k];
            worst = fmax(worst, fabs(sum - entry(row, c)));
        }
    assert_true(worst < 1e-4);
    free(r.weights);
}

static void test_svd_streamed_is_identical_for_any_thread_count_and_kept_table(void **state) {
    svd_result one, two, kept;
    run_svd(1, false, &one);
    run_svd(2, false, &two);
    run_svd(2, true, &kept);
    assert_memory_equal(one.singular, two.singular, sizeof(one.singular));
    assert_memory_equal(one.vectors, two.vectors, sizeof(one.vectors));
    assert_memory_equal(one.weights, two.weights, sizeof(float) * ROWS * 3);
    assert_memory_equal(one.weights, kept.weights, sizeof(float) * ROWS * 3);
    free(one.weights);
    free(two.weights);
    free(kept.weights);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_svd_streamed_finds_the_singular_values_and_reconstructs),
        cmocka_unit_test(test_svd_streamed_is_identical_for_any_thread_count_and_kept_table),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
