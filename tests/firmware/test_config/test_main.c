/*
 * Unity tests of rw_config (the configuration record kept in flash): defaults are valid, carry the
 * parameter defaults, no key and boot counter 0; the CRC-32 is the IEEE one (check value of "123456789");
 * a flipped bit anywhere in the record, another magic, version or size invalidates it; set_key and
 * set_params store and reseal; a change without seal is caught; session ids are epoch + boot counter, a new
 * epoch restarts the counter, out-of-range epochs are refused, the counter never wraps the session id.
 * Run with `pio test -e native`.
 */
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <unity.h>

#include "rw_config.h"
#include "rw_params.h"

static rw_config cfg;

void setUp(void)
{
    memset(&cfg, 0xCC, sizeof cfg);
    rw_config_defaults(&cfg);
}

void tearDown(void) {}

static void test_defaults_are_valid_with_no_key(void)
{
    TEST_ASSERT_TRUE(rw_config_valid(&cfg));
    TEST_ASSERT_EQUAL_HEX32(RW_CONFIG_MAGIC, cfg.magic);
    TEST_ASSERT_EQUAL_UINT16(RW_CONFIG_VERSION, cfg.version);
    TEST_ASSERT_EQUAL_UINT16(sizeof cfg, cfg.size);
    TEST_ASSERT_EQUAL_UINT32(0u, cfg.boot_counter);
    TEST_ASSERT_EQUAL_UINT8(0u, cfg.key_set);
    TEST_ASSERT_EQUAL_UINT8(0u, cfg.password_set);
    TEST_ASSERT_EQUAL_CHAR(0, cfg.wifi_ssid[0]);
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        TEST_ASSERT_EQUAL_FLOAT(rw_param_table[i].default_value, cfg.params[i]);
    }
    /* defaults are the same bytes whatever the memory held before (padding included) */
    rw_config again;
    memset(&again, 0x5A, sizeof again);
    rw_config_defaults(&again);
    TEST_ASSERT_EQUAL_MEMORY(&cfg, &again, sizeof cfg);
}

static void test_crc32_is_the_ieee_crc(void)
{
    TEST_ASSERT_EQUAL_HEX32(0xCBF43926u, rw_crc32("123456789", 9u));
    TEST_ASSERT_EQUAL_HEX32(0x00000000u, rw_crc32("", 0u));
    TEST_ASSERT_EQUAL_HEX32(rw_crc32(&cfg, (uint32_t)offsetof(rw_config, crc32)), cfg.crc32);
}

static void test_any_flipped_bit_invalidates_the_record(void)
{
    uint8_t *bytes = (uint8_t *)&cfg;
    for (size_t bit = 0u; bit < sizeof cfg * 8u; ++bit) {
        bytes[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
        TEST_ASSERT_FALSE_MESSAGE(rw_config_valid(&cfg), "a flipped bit went unnoticed");
        bytes[bit / 8u] ^= (uint8_t)(1u << (bit % 8u));
    }
    TEST_ASSERT_TRUE(rw_config_valid(&cfg));
}

static void test_other_magic_version_or_size_is_refused_even_when_sealed(void)
{
    cfg.version = RW_CONFIG_VERSION + 1u;
    rw_config_seal(&cfg);
    TEST_ASSERT_FALSE(rw_config_valid(&cfg));
    rw_config_defaults(&cfg);
    cfg.size = (uint16_t)(sizeof cfg - 4u);
    rw_config_seal(&cfg);
    TEST_ASSERT_FALSE(rw_config_valid(&cfg));
    rw_config_defaults(&cfg);
    cfg.magic ^= 1u;
    rw_config_seal(&cfg);
    TEST_ASSERT_FALSE(rw_config_valid(&cfg));
}

static void test_set_key_stores_and_reseals(void)
{
    const uint8_t key[RW_KEY_LEN] = { 0u, 1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u, 9u, 10u, 11u, 12u, 13u, 14u, 15u };
    uint32_t crc_before = cfg.crc32;
    rw_config_set_key(&cfg, key);
    TEST_ASSERT_TRUE(rw_config_valid(&cfg));
    TEST_ASSERT_EQUAL_UINT8(1u, cfg.key_set);
    TEST_ASSERT_EQUAL_UINT8_ARRAY(key, cfg.key, RW_KEY_LEN);
    TEST_ASSERT_NOT_EQUAL(crc_before, cfg.crc32);
    /* a change without a seal is caught */
    cfg.key[3] ^= 0x10u;
    TEST_ASSERT_FALSE(rw_config_valid(&cfg));
    rw_config_seal(&cfg);
    TEST_ASSERT_TRUE(rw_config_valid(&cfg));
}

static void test_set_params_stores_and_reseals(void)
{
    float values[RW_PARAM_COUNT];
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        values[i] = rw_param_table[i].default_value;
    }
    values[RW_PARAM_SPEED_KP] = 0.07f;
    uint32_t crc_before = cfg.crc32;
    rw_config_set_params(&cfg, values);
    TEST_ASSERT_TRUE(rw_config_valid(&cfg));
    TEST_ASSERT_EQUAL_FLOAT(0.07f, cfg.params[RW_PARAM_SPEED_KP]);
    TEST_ASSERT_EQUAL_MEMORY(values, cfg.params, sizeof values);
    TEST_ASSERT_NOT_EQUAL(crc_before, cfg.crc32);
    cfg.boot_counter += 1u; /* a new session without a seal */
    TEST_ASSERT_FALSE(rw_config_valid(&cfg));
}

static void test_a_new_epoch_restarts_the_session_range(void)
{
    cfg.boot_counter = 7u;
    rw_config_seal(&cfg);
    rw_config before = cfg;
    TEST_ASSERT_FALSE(rw_config_new_epoch(&cfg, RW_CONFIG_EPOCH_LIMIT));
    TEST_ASSERT_FALSE(rw_config_new_epoch(&cfg, 0xFFFFFFFFu));
    TEST_ASSERT_EQUAL_MEMORY(&before, &cfg, sizeof cfg); /* refused: unchanged */
    TEST_ASSERT_TRUE(rw_config_new_epoch(&cfg, 0x2BADCAFEu));
    TEST_ASSERT_TRUE(rw_config_valid(&cfg));
    TEST_ASSERT_EQUAL_UINT32(0u, cfg.boot_counter);
    TEST_ASSERT_EQUAL_UINT32(1u, cfg.commits);
    TEST_ASSERT_EQUAL_HEX32(0x2BADCAFEu, rw_config_session_id(&cfg));
    TEST_ASSERT_TRUE(rw_config_next_boot(&cfg));
    TEST_ASSERT_TRUE(rw_config_valid(&cfg));
    TEST_ASSERT_EQUAL_HEX32(0x2BADCAFFu, rw_config_session_id(&cfg));
}

static void test_the_boot_counter_never_wraps_the_session_id(void)
{
    TEST_ASSERT_TRUE(rw_config_new_epoch(&cfg, RW_CONFIG_EPOCH_LIMIT - 1u));
    cfg.boot_counter = RW_CONFIG_BOOT_COUNTER_MAX - 1u;
    rw_config_seal(&cfg);
    TEST_ASSERT_TRUE(rw_config_next_boot(&cfg));
    TEST_ASSERT_EQUAL_HEX32(0xFFFFFFFEu, rw_config_session_id(&cfg));
    rw_config before = cfg;
    TEST_ASSERT_FALSE(rw_config_next_boot(&cfg)); /* used up: refused */
    TEST_ASSERT_EQUAL_MEMORY(&before, &cfg, sizeof cfg);
    cfg.boot_counter = RW_CONFIG_BOOT_COUNTER_MAX + 1u; /* out of range even when sealed */
    rw_config_seal(&cfg);
    TEST_ASSERT_FALSE(rw_config_valid(&cfg));
}

static void test_clear_key_forgets_the_key(void)
{
    const uint8_t key[RW_KEY_LEN] = { 9u, 9u, 9u, 9u, 9u, 9u, 9u, 9u, 9u, 9u, 9u, 9u, 9u, 9u, 9u, 9u };
    const uint8_t zero[RW_KEY_LEN] = { 0u };
    rw_config_set_key(&cfg, key);
    rw_config_clear_key(&cfg);
    TEST_ASSERT_TRUE(rw_config_valid(&cfg));
    TEST_ASSERT_EQUAL_UINT8(0u, cfg.key_set);
    TEST_ASSERT_EQUAL_UINT8_ARRAY(zero, cfg.key, RW_KEY_LEN);
}

/* A commit in one piece is the three steps it replaces, byte for byte (one CRC instead of three). */
static void test_commit_in_one_piece_equals_the_three_steps(void)
{
    static const uint8_t key[RW_KEY_LEN] = { 9u, 8u, 7u, 6u, 5u, 4u, 3u, 2u, 1u, 0u, 1u, 2u, 3u, 4u, 5u, 6u };
    float values[RW_PARAM_COUNT];
    for (unsigned i = 0u; i < RW_PARAM_COUNT; ++i) {
        values[i] = rw_param_table[i].default_value * 1.5f;
    }
    rw_config steps;
    rw_config_defaults(&steps);
    TEST_ASSERT_TRUE(rw_config_next_boot(&steps));
    rw_config one = steps;
    TEST_ASSERT_TRUE(rw_config_new_epoch(&steps, 12345u));
    rw_config_set_params(&steps, values);
    rw_config_set_key(&steps, key);
    TEST_ASSERT_TRUE(rw_config_commit(&one, 12345u, values, key));
    TEST_ASSERT_EQUAL_MEMORY(&steps, &one, sizeof one);
    TEST_ASSERT_TRUE(rw_config_valid(&one));
    rw_config no_key = one;
    TEST_ASSERT_TRUE(rw_config_commit(&no_key, 777u, values, NULL));
    TEST_ASSERT_EQUAL_MEMORY(one.key, no_key.key, RW_KEY_LEN);
    TEST_ASSERT_EQUAL_UINT32(2u, no_key.commits);
    const rw_config before = no_key;
    TEST_ASSERT_FALSE(rw_config_commit(&no_key, RW_CONFIG_EPOCH_LIMIT, values, key));
    TEST_ASSERT_EQUAL_MEMORY(&before, &no_key, sizeof no_key);
}

static void test_take_credentials_terminates_blanks_an_unset_password_and_says_what_changed(void)
{
    rw_config c;
    rw_config_defaults(&c);
    memset(c.wifi_ssid, 'S', sizeof c.wifi_ssid); /* no NUL in the record: the copy is cut one short */
    memcpy(c.wifi_password, "secret", 7);
    c.password_set = 0u;
    char ssid[RW_CONFIG_SSID_LEN] = "";
    char password[RW_CONFIG_PASSWORD_LEN] = "";
    TEST_ASSERT_TRUE(rw_config_take_credentials(&c, ssid, password));
    TEST_ASSERT_EQUAL_size_t(sizeof ssid - 1u, strlen(ssid));
    TEST_ASSERT_EQUAL_STRING("", password);
    TEST_ASSERT_FALSE(rw_config_take_credentials(&c, ssid, password));
    c.password_set = 1u;
    TEST_ASSERT_TRUE(rw_config_take_credentials(&c, ssid, password));
    TEST_ASSERT_EQUAL_STRING("secret", password);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_defaults_are_valid_with_no_key);
    RUN_TEST(test_crc32_is_the_ieee_crc);
    RUN_TEST(test_any_flipped_bit_invalidates_the_record);
    RUN_TEST(test_other_magic_version_or_size_is_refused_even_when_sealed);
    RUN_TEST(test_set_key_stores_and_reseals);
    RUN_TEST(test_set_params_stores_and_reseals);
    RUN_TEST(test_commit_in_one_piece_equals_the_three_steps);
    RUN_TEST(test_a_new_epoch_restarts_the_session_range);
    RUN_TEST(test_the_boot_counter_never_wraps_the_session_id);
    RUN_TEST(test_clear_key_forgets_the_key);
    RUN_TEST(test_take_credentials_terminates_blanks_an_unset_password_and_says_what_changed);
    return UNITY_END();
}
