/*
 * Unity tests of rw_float_bits.h: the bit-pattern comparisons give the answers of the C operators on every
 * pair of special and ordinary values (NaN, +-0, +-inf, subnormals, normals), and the half-up rounding
 * equals floor(x + 0.5) of the exact value. Run with `pio test -e native`.
 */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <unity.h>

#include "rw_float_bits.h"

void setUp(void) {}

void tearDown(void) {}

static const float values[] = {
    0.0f, -0.0f, 1.0f, -1.0f, 0.5f, -0.5f, 1.0e-3f, -1.0e-3f, 2.6f, 65535.0f, -65535.0f, FLT_MAX, -FLT_MAX,
    FLT_MIN, -FLT_MIN, 1.0e-40f, -1.0e-40f, INFINITY, -INFINITY, NAN, -NAN, 3.0e38f, 1.0000001f, 0.99999994f,
};
#define N_VALUES (sizeof values / sizeof values[0])

static void test_comparisons_match_the_c_operators(void)
{
    for (unsigned i = 0u; i < N_VALUES; ++i) {
        for (unsigned j = 0u; j < N_VALUES; ++j) {
            const float a = values[i];
            const float b = values[j];
            TEST_ASSERT_EQUAL_INT_MESSAGE(a < b, rw_f32_lt(a, b), "lt");
            TEST_ASSERT_EQUAL_INT_MESSAGE(a <= b, rw_f32_le(a, b), "le");
            TEST_ASSERT_EQUAL_INT_MESSAGE(a > b, rw_f32_gt(a, b), "gt");
            TEST_ASSERT_EQUAL_INT_MESSAGE(a >= b, rw_f32_ge(a, b), "ge");
        }
    }
}

static void test_classification_matches_math_h(void)
{
    for (unsigned i = 0u; i < N_VALUES; ++i) {
        const float x = values[i];
        TEST_ASSERT_EQUAL_INT(isfinite(x) != 0, rw_f32_finite(x));
        TEST_ASSERT_EQUAL_INT(isnan(x) != 0, rw_f32_isnan(x));
        TEST_ASSERT_EQUAL_INT(x > 0.0f, rw_f32_positive(x));
        TEST_ASSERT_EQUAL_INT(x > 0.0f && isfinite(x), rw_f32_positive_finite(x));
    }
}

static void test_same_is_bit_equality(void)
{
    TEST_ASSERT_TRUE(rw_f32_same(2.6f, 2.6f));
    TEST_ASSERT_FALSE(rw_f32_same(0.0f, -0.0f)); /* equal values, different bits: a cache must not match */
    TEST_ASSERT_TRUE(rw_f32_same(NAN, NAN));
    TEST_ASSERT_FALSE(rw_f32_same(1.0f, 1.0000001f));
}

static void test_round_half_up_is_floor_of_x_plus_half(void)
{
    const float xs[] = {0.0f, 0.25f, 0.49999997f, 0.5f, 0.75f, 1.5f, 2.5f, 1234.4999f, 1234.5f, 999.99994f,
                        65534.5f, 8388607.5f, 16777215.0f, 1.0e-20f, -3.0f};
    for (unsigned i = 0u; i < sizeof xs / sizeof xs[0]; ++i) {
        const double x = (double)xs[i];
        const uint32_t expected = x < 0.5 ? 0u : (uint32_t)floor(x + 0.5);
        TEST_ASSERT_EQUAL_UINT32(expected, rw_f32_round_half_up_u24(xs[i]));
    }
}

/* p 2^e2 as a float (exact: p <= 2^24). */
static float rebuild(uint32_t p, int32_t e2)
{
    return ldexpf((float)p, e2);
}

/* x k_odd 2^k_shift rounded by rw_f32_mul_small equals the float multiplication, bit for bit, over a
 * sweep of rope speeds, guide positions and wheel speeds (and their neighbours one ulp apart). */
static void test_mul_small_equals_the_float_multiply(void)
{
    uint32_t state = 12345u;
    for (unsigned i = 0u; i < 200000u; ++i) {
        state = state * 1664525u + 1013904223u; /* LCG: reproducible */
        const float x = (float)(state >> 8) * (1.0f / 16777216.0f) * (i % 2u ? 70.0f : 2000.0f);
        volatile float k1000 = 1000.0f;
        volatile float k60 = 60.0f;
        const float want1000 = x * k1000;
        const float want60 = x * k60;
        int32_t e2;
        uint32_t p = rw_f32_mul_small(x, 125u, 3, &e2);
        TEST_ASSERT_EQUAL_FLOAT(want1000, rebuild(p, e2));
        TEST_ASSERT_TRUE(rebuild(p, e2) == want1000);
        p = rw_f32_mul_small(x, 15u, 2, &e2);
        TEST_ASSERT_TRUE(rebuild(p, e2) == want60);
        p = rw_f32_mul_small(-x, 125u, 3, &e2); /* the magnitude */
        TEST_ASSERT_TRUE(rebuild(p, e2) == want1000);
    }
    int32_t e2;
    TEST_ASSERT_EQUAL_UINT32(0u, rw_f32_mul_small(0.0f, 125u, 3, &e2));
    TEST_ASSERT_EQUAL_UINT32(0u, rw_f32_mul_small(1.0e-40f, 125u, 3, &e2));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_comparisons_match_the_c_operators);
    RUN_TEST(test_classification_matches_math_h);
    RUN_TEST(test_same_is_bit_equality);
    RUN_TEST(test_round_half_up_is_floor_of_x_plus_half);
    RUN_TEST(test_mul_small_equals_the_float_multiply);
    return UNITY_END();
}
