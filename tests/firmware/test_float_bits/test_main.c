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

/* rw_f32_ms_past answers what (float)elapsed_ms > / >= threshold_s * 1000.0f answers, for the special
 * thresholds and a sweep of timeouts around every elapsed value that could straddle them. */
static void test_ms_past_equals_the_float_comparison(void)
{
    const float thresholds[] = {0.0f, -0.0f, -1.0f, 1.0e-40f, 1.0e-4f, 0.0005f, 0.001f, 0.2f, 0.3f, 0.5f,
                                1.0f, 1.5f, 2.0f, 3.0f, 5.0f, 0.123456f, 16777.215f, 16777.216f, 20000.0f,
                                4.0e6f, FLT_MAX, INFINITY, -INFINITY, NAN};
    const uint32_t extra[] = {0u, 1u, 16777215u, 16777216u, 16777217u, 20000001u, 0xFFFFFFFFu};
    for (unsigned i = 0u; i < sizeof thresholds / sizeof thresholds[0]; ++i) {
        const float t = thresholds[i];
        volatile float k1000 = 1000.0f;
        const float limit = t * k1000;
        const double centre = isfinite(limit) && limit > 0.0f && limit < 4.0e9f ? floor((double)limit) : 0.0;
        for (int32_t d = -3; d <= 3; ++d) {
            const double e = centre + (double)d;
            const uint32_t elapsed = e < 0.0 ? 0u : (uint32_t)e;
            TEST_ASSERT_EQUAL_INT((float)elapsed > limit, rw_f32_ms_past(elapsed, t, false));
            TEST_ASSERT_EQUAL_INT((float)elapsed >= limit, rw_f32_ms_past(elapsed, t, true));
        }
        for (unsigned j = 0u; j < sizeof extra / sizeof extra[0]; ++j) {
            TEST_ASSERT_EQUAL_INT((float)extra[j] > limit, rw_f32_ms_past(extra[j], t, false));
            TEST_ASSERT_EQUAL_INT((float)extra[j] >= limit, rw_f32_ms_past(extra[j], t, true));
        }
    }
    uint32_t state = 777u;
    for (unsigned i = 0u; i < 100000u; ++i) {
        state = state * 1664525u + 1013904223u;
        const float t = (float)(state >> 8) * (1.0f / 16777216.0f) * 100.0f;
        volatile float k1000 = 1000.0f;
        const float limit = t * k1000;
        const uint32_t elapsed = (uint32_t)limit + (state & 3u) - 1u;
        TEST_ASSERT_EQUAL_INT((float)elapsed > limit, rw_f32_ms_past(elapsed, t, false));
        TEST_ASSERT_EQUAL_INT((float)elapsed >= limit, rw_f32_ms_past(elapsed, t, true));
    }
}

/* Q16.16 conversions: to_q16 rounds x 65536 to nearest and saturates, from_q16 equals the C conversion
 * (float)q / 65536 (exact under 2^24, rounded to nearest even above), over specials and a sweep. */
static void test_q16_conversions(void)
{
    TEST_ASSERT_EQUAL_INT32(0, rw_f32_to_q16(NAN));
    TEST_ASSERT_EQUAL_INT32(INT32_MAX, rw_f32_to_q16(INFINITY));
    TEST_ASSERT_EQUAL_INT32(-INT32_MAX, rw_f32_to_q16(-INFINITY));
    TEST_ASSERT_EQUAL_INT32(INT32_MAX, rw_f32_to_q16(32768.0f));
    TEST_ASSERT_EQUAL_INT32(0x7FFFFF80, rw_f32_to_q16(32767.998f));
    TEST_ASSERT_EQUAL_INT32(0, rw_f32_to_q16(-0.0f));
    TEST_ASSERT_EQUAL_INT32(0, rw_f32_to_q16(1.0e-40f));
    TEST_ASSERT_EQUAL_INT32(1, rw_f32_to_q16(1.0f / 65536.0f));
    TEST_ASSERT_EQUAL_INT32(1, rw_f32_to_q16(0.5f / 65536.0f)); /* half: away from zero */
    TEST_ASSERT_EQUAL_INT32(0, rw_f32_to_q16(0.49f / 65536.0f));
    TEST_ASSERT_EQUAL_INT32(-65536 * 5 - 32768, rw_f32_to_q16(-5.5f));
    uint32_t state = 99u;
    for (unsigned i = 0u; i < 200000u; ++i) {
        state = state * 1664525u + 1013904223u;
        const float x = ((float)(state >> 8) * (1.0f / 16777216.0f) - 0.5f) * (i % 3u == 0u ? 60000.0f : 40.0f);
        const double exact = (double)x * 65536.0;
        const double rounded = exact < 0.0 ? -floor(-exact + 0.5) : floor(exact + 0.5);
        TEST_ASSERT_EQUAL_INT32((int32_t)rounded, rw_f32_to_q16(x));
        const int32_t q = (int32_t)(state ^ (state << 7));
        TEST_ASSERT_TRUE((float)q / 65536.0f == rw_f32_from_q16(q));
        const int32_t small = (int32_t)(state >> 9) - (1 << 22);
        TEST_ASSERT_TRUE((float)small / 65536.0f == rw_f32_from_q16(small));
    }
    /* other fixed points: Q32 of a tick period, Q0 */
    TEST_ASSERT_EQUAL_INT32(8589935, rw_f32_to_fixed(0.002f, 32u)); /* 0.002 2^32 = 8589934.6 */
    TEST_ASSERT_EQUAL_INT32(INT32_MAX, rw_f32_to_fixed(0.5f, 32u));
    TEST_ASSERT_EQUAL_INT32(1073741824, rw_f32_to_fixed(0.25f, 32u));
    TEST_ASSERT_EQUAL_INT32(-3, rw_f32_to_fixed(-2.5f, 0u));
    TEST_ASSERT_EQUAL_INT32(INT32_MAX, rw_f32_to_fixed(3.0e9f, 0u));
    for (unsigned i = 0u; i < 20000u; ++i) {
        state = state * 1664525u + 1013904223u;
        const float x = (float)(state >> 8) * (1.0f / 16777216.0f) * 0.3f;
        const double exact = (double)x * 4294967296.0;
        TEST_ASSERT_EQUAL_INT32((int32_t)floor(exact + 0.5), rw_f32_to_fixed(x, 32u));
    }
    TEST_ASSERT_TRUE(rw_f32_from_q16(INT32_MIN) == -32768.0f);
    TEST_ASSERT_TRUE(rw_f32_from_q16(INT32_MAX) == 32768.0f);
    TEST_ASSERT_TRUE(rw_f32_from_q16(0) == 0.0f);
}

/* The inline long multiplies equal the 64-bit products, over the extremes and a sweep. */
static void test_long_multiply(void)
{
    const uint32_t edges[] = {0u, 1u, 0xFFFFu, 0x10000u, 0x7FFFFFFFu, 0x80000000u, 0xFFFFFFFFu, 123456789u};
    for (unsigned i = 0u; i < sizeof edges / sizeof edges[0]; ++i) {
        for (unsigned j = 0u; j < sizeof edges / sizeof edges[0]; ++j) {
            TEST_ASSERT_TRUE((uint64_t)edges[i] * edges[j] == rw_mul_u32_u64(edges[i], edges[j]));
            const int32_t a = (int32_t)edges[i];
            const int32_t b = (int32_t)edges[j];
            TEST_ASSERT_TRUE((int64_t)a * b == rw_mul_s32_s64(a, b));
        }
    }
    uint32_t state = 4242u;
    for (unsigned i = 0u; i < 200000u; ++i) {
        state = state * 1664525u + 1013904223u;
        const uint32_t a = state;
        const uint32_t b = state * 2654435761u;
        TEST_ASSERT_TRUE((uint64_t)a * b == rw_mul_u32_u64(a, b));
        TEST_ASSERT_TRUE((int64_t)(int32_t)a * (int32_t)b == rw_mul_s32_s64((int32_t)a, (int32_t)b));
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_comparisons_match_the_c_operators);
    RUN_TEST(test_classification_matches_math_h);
    RUN_TEST(test_same_is_bit_equality);
    RUN_TEST(test_round_half_up_is_floor_of_x_plus_half);
    RUN_TEST(test_mul_small_equals_the_float_multiply);
    RUN_TEST(test_ms_past_equals_the_float_comparison);
    RUN_TEST(test_q16_conversions);
    RUN_TEST(test_long_multiply);
    return UNITY_END();
}
