/*
 * Unity tests of rw_link_status, what the board shows a person about its WiFi link: the status LED's pattern per
 * link state (steady on for NO_MODULE, 5 Hz while connecting, a 50 ms flash a second when up, two flashes every
 * 2 s when not provisioned) and the USB line per state. Run with `pio test -e native`.
 */
#include <stdint.h>
#include <string.h>
#include <unity.h>

#include "rw_link_status.h"
#include "rw_wifi_supervisor.h"

void setUp(void) {}

void tearDown(void) {}

/* Milliseconds lit in [t0, t0 + span_ms) and how often the LED switched. */
static uint32_t lit_ms(uint8_t state, uint32_t t0, uint32_t span_ms, uint32_t *changes)
{
    uint32_t lit = 0u;
    bool last = rw_link_status_led_on(t0, state);
    *changes = 0u;
    for (uint32_t i = 0u; i < span_ms; ++i) {
        const bool on = rw_link_status_led_on(t0 + i, state);
        lit += on ? 1u : 0u;
        *changes += on != last ? 1u : 0u;
        last = on;
    }
    return lit;
}

static void test_no_module_is_steady_on(void)
{
    uint32_t changes = 0u;
    TEST_ASSERT_EQUAL_UINT32(10000u, lit_ms(RW_WIFI_NO_MODULE, 123u, 10000u, &changes));
    TEST_ASSERT_EQUAL_UINT32(0u, changes);
}

static void test_connecting_blinks_at_5_hz(void)
{
    uint32_t changes = 0u;
    TEST_ASSERT_EQUAL_UINT32(5000u, lit_ms(RW_WIFI_CONNECTING, 0u, 10000u, &changes));
    TEST_ASSERT_EQUAL_UINT32(99u, changes);
}

static void test_up_flashes_50_ms_a_second(void)
{
    uint32_t changes = 0u;
    TEST_ASSERT_EQUAL_UINT32(500u, lit_ms(RW_WIFI_UP, 0u, 10000u, &changes));
    TEST_ASSERT_EQUAL_UINT32(19u, changes);
}

static void test_not_provisioned_flashes_twice_every_2_s(void)
{
    uint32_t changes = 0u;
    TEST_ASSERT_EQUAL_UINT32(1000u, lit_ms(RW_WIFI_NOT_PROVISIONED, 0u, 10000u, &changes));
    TEST_ASSERT_EQUAL_UINT32(19u, changes);
}

static void test_the_usb_line_names_the_state(void)
{
    TEST_ASSERT_EQUAL_STRING("wifi UP", rw_link_status_text(RW_WIFI_UP));
    TEST_ASSERT_EQUAL_STRING("wifi CONNECTING", rw_link_status_text(RW_WIFI_CONNECTING));
    TEST_ASSERT_NOT_NULL(strstr(rw_link_status_text(RW_WIFI_NO_MODULE), "does not answer"));
    TEST_ASSERT_NOT_NULL(strstr(rw_link_status_text(RW_WIFI_NOT_PROVISIONED), "provision over USB"));
    TEST_ASSERT_EQUAL_STRING("wifi ?", rw_link_status_text(200u));
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_no_module_is_steady_on);
    RUN_TEST(test_connecting_blinks_at_5_hz);
    RUN_TEST(test_up_flashes_50_ms_a_second);
    RUN_TEST(test_not_provisioned_flashes_twice_every_2_s);
    RUN_TEST(test_the_usb_line_names_the_state);
    return UNITY_END();
}
