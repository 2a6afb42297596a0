/*
 * Unity tests of rw_params: defaults from the generated table, range checks without clamping (NaN,
 * infinity, out of [min, max], fractions for integer parameters), locked parameters only while
 * DISARMED, unknown ids, the rules between parameters (PARAM_CONFLICT). Every check runs over the whole table. Run with `pio test -e native`.
 */
#include <math.h>
#include <stdint.h>
#include <unity.h>

#include "rw_params.h"

static rw_params params;

void setUp(void)
{
    rw_params_init_defaults(&params);
}

void tearDown(void) {}

static void test_defaults_come_from_the_table_and_lie_in_range(void)
{
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        const rw_param_info *info = &rw_param_table[i];
        TEST_ASSERT_EQUAL_FLOAT(info->default_value, rw_params_get(&params, (rw_param_id)i));
        TEST_ASSERT_TRUE_MESSAGE(info->min_value <= info->default_value && info->default_value <= info->max_value,
                                 info->name);
        TEST_ASSERT_EQUAL_INT_MESSAGE(RW_DECODE_OK, rw_params_check(&params, (uint8_t)i, info->default_value, true),
                                      info->name);
    }
}

/* Defaults, with the partners of the rules between parameters moved out of the way (the ToV guard at its
 * lowest, 0.5 m/s x 1.0), so that every parameter's own limits can be reached from here. */
static void permissive_baseline(void)
{
    rw_params_init_defaults(&params);
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_params_set(&params, RW_PARAM_TOV_MPS, 0.5f, true));
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_params_set(&params, RW_PARAM_TOV_MARGIN, 1.0f, true));
}

static void test_limits_are_accepted_just_outside_refused_never_clamped(void)
{
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        const rw_param_info *info = &rw_param_table[i];
        const uint8_t id = (uint8_t)i;
        permissive_baseline();
        TEST_ASSERT_EQUAL_INT_MESSAGE(RW_DECODE_OK, rw_params_set(&params, id, info->min_value, true), info->name);
        TEST_ASSERT_EQUAL_FLOAT(info->min_value, params.value[i]);
        TEST_ASSERT_EQUAL_INT_MESSAGE(RW_DECODE_OK, rw_params_set(&params, id, info->max_value, true), info->name);
        TEST_ASSERT_EQUAL_FLOAT(info->max_value, params.value[i]);
        const float below = nextafterf(info->min_value, -INFINITY);
        const float above = nextafterf(info->max_value, INFINITY);
        TEST_ASSERT_EQUAL_INT_MESSAGE(RW_NACK_REASON_OUT_OF_RANGE, rw_params_set(&params, id, below, true), info->name);
        TEST_ASSERT_EQUAL_INT_MESSAGE(RW_NACK_REASON_OUT_OF_RANGE, rw_params_set(&params, id, above, true), info->name);
        TEST_ASSERT_EQUAL_FLOAT_MESSAGE(info->max_value, params.value[i], "a refused value is not stored");
    }
}

static void test_non_finite_values_are_refused(void)
{
    const float bad[] = { NAN, -NAN, INFINITY, -INFINITY };
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        for (unsigned k = 0u; k < sizeof bad / sizeof bad[0]; ++k) {
            TEST_ASSERT_EQUAL_INT_MESSAGE(RW_NACK_REASON_OUT_OF_RANGE, rw_params_set(&params, (uint8_t)i, bad[k], true),
                                          rw_param_table[i].name);
            TEST_ASSERT_EQUAL_FLOAT(rw_param_table[i].default_value, params.value[i]);
        }
    }
}

static void test_integer_parameters_refuse_fractions(void)
{
    unsigned integers = 0u;
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        const rw_param_info *info = &rw_param_table[i];
        if ((info->flags & RW_PARAM_FLAG_INTEGER) == 0u) {
            continue;
        }
        ++integers;
        const float whole = floorf(info->min_value) + 1.0f;
        TEST_ASSERT_EQUAL_INT_MESSAGE(RW_DECODE_OK, rw_params_check(&params, (uint8_t)i, whole, true), info->name);
        TEST_ASSERT_EQUAL_INT_MESSAGE(RW_NACK_REASON_OUT_OF_RANGE,
                                      rw_params_check(&params, (uint8_t)i, whole + 0.5f, true), info->name);
    }
    TEST_ASSERT_TRUE_MESSAGE(integers > 0u, "the table has integer parameters (encoder_counts_per_rev)");
    TEST_ASSERT_EQUAL_INT(RW_NACK_REASON_OUT_OF_RANGE,
                          rw_params_set(&params, RW_PARAM_ENCODER_COUNTS_PER_REV, 64.25f, true));
    TEST_ASSERT_EQUAL_FLOAT(64.0f, rw_params_get(&params, RW_PARAM_ENCODER_COUNTS_PER_REV));
}

static void test_locked_parameters_only_while_disarmed(void)
{
    unsigned locked = 0u;
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        const rw_param_info *info = &rw_param_table[i];
        const float v = info->max_value;
        if ((info->flags & RW_PARAM_FLAG_LOCKED) != 0u) {
            ++locked;
            TEST_ASSERT_EQUAL_INT_MESSAGE(RW_NACK_REASON_PARAM_LOCKED, rw_params_set(&params, (uint8_t)i, v, false),
                                          info->name);
            TEST_ASSERT_EQUAL_FLOAT(info->default_value, params.value[i]);
        } else {
            TEST_ASSERT_EQUAL_INT_MESSAGE(RW_DECODE_OK, rw_params_set(&params, (uint8_t)i, v, false), info->name);
        }
        TEST_ASSERT_EQUAL_INT_MESSAGE(RW_DECODE_OK, rw_params_set(&params, (uint8_t)i, v, true), info->name);
        TEST_ASSERT_EQUAL_FLOAT(v, params.value[i]);
    }
    TEST_ASSERT_TRUE(locked > 0u);
    TEST_ASSERT_EQUAL_INT(RW_NACK_REASON_PARAM_LOCKED, rw_params_check(&params, RW_PARAM_ESC_MIN_US, 1100.0f, false));
}

static void test_parameters_that_must_hold_together_are_checked_together(void)
{
    /* guide_min_mm < guide_max_mm: the second of "min 150, max 50" is refused, nothing changes */
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_params_set(&params, RW_PARAM_GUIDE_MIN_MM, 150.0f, true));
    TEST_ASSERT_EQUAL_INT(RW_NACK_REASON_PARAM_CONFLICT, rw_params_set(&params, RW_PARAM_GUIDE_MAX_MM, 50.0f, true));
    TEST_ASSERT_EQUAL_UINT8(RW_PARAM_GUIDE_MIN_MM, rw_params_conflict(&params, RW_PARAM_GUIDE_MAX_MM, 50.0f));
    TEST_ASSERT_EQUAL_INT(RW_NACK_REASON_PARAM_CONFLICT, rw_params_check(&params, RW_PARAM_GUIDE_MAX_MM, 150.0f, true));
    TEST_ASSERT_EQUAL_FLOAT(180.0f, rw_params_get(&params, RW_PARAM_GUIDE_MAX_MM));
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_params_set(&params, RW_PARAM_GUIDE_MAX_MM, 150.5f, true));
    TEST_ASSERT_EQUAL_UINT8(RW_PARAM_GUIDE_MAX_MM, rw_params_conflict(&params, RW_PARAM_GUIDE_MIN_MM, 151.0f));
    /* tov_mps x tov_margin <= max_rope_speed_mps, from either side, the limit itself accepted */
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_params_set(&params, RW_PARAM_MAX_ROPE_SPEED_MPS, 5.0f, true));
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_params_set(&params, RW_PARAM_TOV_MARGIN, 1.25f, true));
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_params_set(&params, RW_PARAM_TOV_MPS, 4.0f, true)); /* 5.0: the limit */
    TEST_ASSERT_EQUAL_INT(RW_NACK_REASON_PARAM_CONFLICT, rw_params_set(&params, RW_PARAM_TOV_MPS, 4.5f, true));
    TEST_ASSERT_EQUAL_UINT8(RW_PARAM_MAX_ROPE_SPEED_MPS, rw_params_conflict(&params, RW_PARAM_TOV_MARGIN, 1.5f));
    TEST_ASSERT_EQUAL_UINT8(RW_PARAM_TOV_MPS, rw_params_conflict(&params, RW_PARAM_MAX_ROPE_SPEED_MPS, 4.9f));
    TEST_ASSERT_EQUAL_FLOAT(4.0f, rw_params_get(&params, RW_PARAM_TOV_MPS));
    /* parameters outside every rule never conflict */
    TEST_ASSERT_EQUAL_UINT8(RW_PARAM_COUNT, rw_params_conflict(&params, RW_PARAM_SPEED_KP, 1.0f));
}

static void test_range_is_checked_before_the_lock(void)
{
    /* An out-of-range value for a locked parameter while armed is OUT_OF_RANGE: the value is wrong
     * whatever the state. */
    TEST_ASSERT_EQUAL_INT(RW_NACK_REASON_OUT_OF_RANGE, rw_params_check(&params, RW_PARAM_ESC_MIN_US, 5000.0f, false));
}

static void test_unknown_ids_are_refused(void)
{
    TEST_ASSERT_EQUAL_INT(RW_NACK_REASON_UNKNOWN_PARAM, rw_params_check(&params, (uint8_t)RW_PARAM_COUNT, 1.0f, true));
    TEST_ASSERT_EQUAL_INT(RW_NACK_REASON_UNKNOWN_PARAM, rw_params_set(&params, 255u, 1.0f, true));
}

static void test_named_ranges_of_the_speed_loop(void)
{
    TEST_ASSERT_EQUAL_INT(RW_DECODE_OK, rw_params_set(&params, RW_PARAM_TELEMETRY_RATE_HZ, 100.0f, false));
    TEST_ASSERT_EQUAL_INT(RW_NACK_REASON_OUT_OF_RANGE, rw_params_set(&params, RW_PARAM_TELEMETRY_RATE_HZ, 0.0f, false));
    TEST_ASSERT_EQUAL_INT(RW_NACK_REASON_OUT_OF_RANGE, rw_params_set(&params, RW_PARAM_TOV_MARGIN, 0.99f, false));
    TEST_ASSERT_EQUAL_INT(RW_NACK_REASON_OUT_OF_RANGE, rw_params_set(&params, RW_PARAM_SPEED_KP, -0.001f, false));
    TEST_ASSERT_EQUAL_INT(RW_NACK_REASON_OUT_OF_RANGE,
                          rw_params_set(&params, RW_PARAM_HEARTBEAT_TIMEOUT_S, 0.05f, false));
    TEST_ASSERT_EQUAL_FLOAT(100.0f, rw_params_get(&params, RW_PARAM_TELEMETRY_RATE_HZ));
}

/* Every parameter names the modules it feeds (what a PARAM_SET converts again); a parameter settable in flight
 * feeds at most one of the speed loop's modules, so the speed step sees its old or its new gains, never a mix. */
static void test_each_parameter_knows_its_modules(void)
{
    TEST_ASSERT_EQUAL_HEX16(RW_PARAM_MODULE_SPEED_PI, rw_params_modules(RW_PARAM_SPEED_KP));
    TEST_ASSERT_EQUAL_HEX16(RW_PARAM_MODULE_SPEED_PI, rw_params_modules(RW_PARAM_SPEED_KI));
    TEST_ASSERT_EQUAL_HEX16(RW_PARAM_MODULE_TOV_GUARD, rw_params_modules(RW_PARAM_TOV_MPS));
    TEST_ASSERT_EQUAL_HEX16(RW_PARAM_MODULE_SPINDLE, rw_params_modules(RW_PARAM_SPINDLE_KP_PER_S));
    TEST_ASSERT_EQUAL_HEX16(RW_PARAM_MODULE_LOAD_MONITOR, rw_params_modules(RW_PARAM_LOAD_LOSS_DROP_N));
    TEST_ASSERT_EQUAL_HEX16(RW_PARAM_MODULE_THROTTLE | RW_PARAM_MODULE_LOAD_MONITOR,
                            rw_params_modules(RW_PARAM_MOTOR_KV_RPM_PER_V));
    TEST_ASSERT_EQUAL_HEX16(RW_PARAM_MODULE_NONE, rw_params_modules(RW_PARAM_HEARTBEAT_TIMEOUT_S));
    TEST_ASSERT_EQUAL_HEX16(RW_PARAM_MODULE_NONE, rw_params_modules((uint8_t)RW_PARAM_COUNT));
    TEST_ASSERT_EQUAL_HEX16(RW_PARAM_MODULE_NONE, rw_params_modules(255u));
    for (unsigned id = 0u; id < RW_PARAM_COUNT; ++id) {
        const uint16_t modules = rw_params_modules((uint8_t)id);
        TEST_ASSERT_EQUAL_HEX16(0u, modules & (uint16_t)~RW_PARAM_MODULE_ALL);
        const unsigned speed = modules & RW_PARAM_MODULES_SPEED_LOOP;
        const bool at_most_one = (speed & (speed - 1u)) == 0u;
        TEST_ASSERT_TRUE_MESSAGE(at_most_one || (rw_param_table[id].flags & RW_PARAM_FLAG_LOCKED) != 0u,
                                 rw_param_table[id].name);
    }
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_defaults_come_from_the_table_and_lie_in_range);
    RUN_TEST(test_limits_are_accepted_just_outside_refused_never_clamped);
    RUN_TEST(test_non_finite_values_are_refused);
    RUN_TEST(test_integer_parameters_refuse_fractions);
    RUN_TEST(test_locked_parameters_only_while_disarmed);
    RUN_TEST(test_parameters_that_must_hold_together_are_checked_together);
    RUN_TEST(test_range_is_checked_before_the_lock);
    RUN_TEST(test_unknown_ids_are_refused);
    RUN_TEST(test_each_parameter_knows_its_modules);
    RUN_TEST(test_named_ranges_of_the_speed_loop);
    return UNITY_END();
}
