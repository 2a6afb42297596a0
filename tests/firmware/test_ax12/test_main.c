/*
 * Unity tests of rw_ax12 (AX-12A register conversions). Run with `pio test -e native`.
 * Position 0-1023 over 300 degrees; speed and load 10-bit magnitude + bit 10 = clockwise;
 * + = counter-clockwise = the guide retracts; wheel-mode 1023 = the 59 rpm no-load speed.
 */
#include <math.h>
#include <unity.h>

#include "rw_ax12.h"

#define DEG_S_PER_SPEED_UNIT (0.111f * 6.0f)
#define NO_LOAD_DEG_S (59.0f * 6.0f)

void setUp(void) {}

void tearDown(void) {}

static void test_position_edges_and_round_trip(void)
{
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rw_ax12_position_deg(0u));
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 300.0f, rw_ax12_position_deg(1023u));
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 300.0f, rw_ax12_position_deg(1024u)); /* out of range saturates */
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, 300.0f, rw_ax12_position_deg(2047u));
    float previous = -1.0f;
    for (uint16_t raw = 0u; raw <= 1023u; ++raw) {
        const float deg = rw_ax12_position_deg(raw);
        TEST_ASSERT_EQUAL_INT(raw, (int)lroundf(deg * 1023.0f / 300.0f));
        TEST_ASSERT_TRUE(deg > previous);
        previous = deg;
    }
}

static void test_speed_edges_and_direction_bit(void)
{
    TEST_ASSERT_EQUAL_FLOAT(0.0f, rw_ax12_speed_deg_s(0u));
    TEST_ASSERT_FLOAT_WITHIN(1e-4f, DEG_S_PER_SPEED_UNIT, rw_ax12_speed_deg_s(1u));
    TEST_ASSERT_FLOAT_WITHIN(1e-2f, 1023.0f * DEG_S_PER_SPEED_UNIT, rw_ax12_speed_deg_s(1023u));
    TEST_ASSERT_FLOAT_WITHIN(1e-6f, 0.0f, rw_ax12_speed_deg_s(1024u)); /* clockwise zero */
    TEST_ASSERT_FLOAT_WITHIN(1e-2f, -1023.0f * DEG_S_PER_SPEED_UNIT, rw_ax12_speed_deg_s(2047u));
    for (uint16_t m = 0u; m <= 1023u; ++m) {
        TEST_ASSERT_EQUAL_FLOAT(-rw_ax12_speed_deg_s(m), rw_ax12_speed_deg_s((uint16_t)(m | RW_AX12_DIRECTION_BIT)));
    }
}

static void test_load_edges_and_direction_bit(void)
{
    TEST_ASSERT_EQUAL_INT16(0, rw_ax12_load_permille(0u));
    TEST_ASSERT_EQUAL_INT16(1023, rw_ax12_load_permille(1023u));
    TEST_ASSERT_EQUAL_INT16(0, rw_ax12_load_permille(1024u));
    TEST_ASSERT_EQUAL_INT16(-100, rw_ax12_load_permille(1124u));
    TEST_ASSERT_EQUAL_INT16(-1023, rw_ax12_load_permille(2047u));
}

static void test_moving_speed_round_trip_every_magnitude_with_sign(void)
{
    TEST_ASSERT_EQUAL_UINT16(1023u, rw_ax12_moving_speed_raw(NO_LOAD_DEG_S));
    TEST_ASSERT_EQUAL_UINT16(2047u, rw_ax12_moving_speed_raw(-NO_LOAD_DEG_S));
    TEST_ASSERT_EQUAL_UINT16(0u, rw_ax12_moving_speed_raw(0.0f));
    TEST_ASSERT_EQUAL_UINT16(0u, rw_ax12_moving_speed_raw(-0.0f));
    for (uint16_t m = 0u; m <= 1023u; ++m) {
        const float deg_s = (float)m * NO_LOAD_DEG_S / 1023.0f;
        TEST_ASSERT_EQUAL_UINT16(m, rw_ax12_moving_speed_raw(deg_s));
        /* clockwise = bit 10; a zero magnitude never carries the direction bit */
        TEST_ASSERT_EQUAL_UINT16(m != 0u ? (uint16_t)(m | RW_AX12_DIRECTION_BIT) : 0u, rw_ax12_moving_speed_raw(-deg_s));
    }
}

static void test_moving_speed_saturates_and_keeps_direction(void)
{
    TEST_ASSERT_EQUAL_UINT16(1023u, rw_ax12_moving_speed_raw(NO_LOAD_DEG_S * 1.001f));
    TEST_ASSERT_EQUAL_UINT16(1023u, rw_ax12_moving_speed_raw(1.0e4f));
    TEST_ASSERT_EQUAL_UINT16(1023u, rw_ax12_moving_speed_raw(3.0e38f));
    TEST_ASSERT_EQUAL_UINT16(2047u, rw_ax12_moving_speed_raw(-1.0e4f));
    TEST_ASSERT_EQUAL_UINT16(2047u, rw_ax12_moving_speed_raw(-3.0e38f));
}

static void test_non_finite_speed_is_stop(void)
{
    TEST_ASSERT_EQUAL_UINT16(0u, rw_ax12_moving_speed_raw(NAN));
    TEST_ASSERT_EQUAL_UINT16(0u, rw_ax12_moving_speed_raw(-NAN));
    TEST_ASSERT_EQUAL_UINT16(0u, rw_ax12_moving_speed_raw(INFINITY));
    TEST_ASSERT_EQUAL_UINT16(0u, rw_ax12_moving_speed_raw(-INFINITY));
}

static void test_under_half_a_unit_is_stop_without_direction(void)
{
    const float half_unit = 0.5f * NO_LOAD_DEG_S / 1023.0f;
    TEST_ASSERT_EQUAL_UINT16(0u, rw_ax12_moving_speed_raw(0.9f * half_unit));
    TEST_ASSERT_EQUAL_UINT16(0u, rw_ax12_moving_speed_raw(-0.9f * half_unit));
    TEST_ASSERT_EQUAL_UINT16(1u, rw_ax12_moving_speed_raw(1.1f * half_unit));
    TEST_ASSERT_EQUAL_UINT16(1025u, rw_ax12_moving_speed_raw(-1.1f * half_unit));
}

static void test_register_never_has_bits_above_the_direction_bit(void)
{
    for (int k = -2000; k <= 2000; ++k) {
        const uint16_t raw = rw_ax12_moving_speed_raw((float)k * 0.5f);
        TEST_ASSERT_EQUAL_UINT16(0u, raw & (uint16_t)~0x07FFu);
        TEST_ASSERT_TRUE((raw & RW_AX12_MAGNITUDE_MASK) <= 1023u);
        TEST_ASSERT_EQUAL((k < 0 && (raw & RW_AX12_MAGNITUDE_MASK) != 0u), (raw & RW_AX12_DIRECTION_BIT) != 0u);
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_position_edges_and_round_trip);
    RUN_TEST(test_speed_edges_and_direction_bit);
    RUN_TEST(test_load_edges_and_direction_bit);
    RUN_TEST(test_moving_speed_round_trip_every_magnitude_with_sign);
    RUN_TEST(test_moving_speed_saturates_and_keeps_direction);
    RUN_TEST(test_non_finite_speed_is_stop);
    RUN_TEST(test_under_half_a_unit_is_stop_without_direction);
    RUN_TEST(test_register_never_has_bits_above_the_direction_bit);
    return UNITY_END();
}
