/*
 * Unity tests of rw_spindle_exchange, the split spindle transaction between the control tick and the bus
 * side: a reading reaches the core at the step after its request; a lost reply or a late bus is a step
 * without a reading (counted); only the latest post is written, writes before reads; a tick between a job and
 * its result loses nothing. Run with `pio test -e native`.
 */
#include <stdint.h>
#include <unity.h>

#include "rw_spindle_exchange.h"

static rw_spindle_exchange ex;

void setUp(void)
{
    rw_spindle_exchange_init(&ex);
}

void tearDown(void) {}

static rw_spindle_reading reading_at(uint16_t position_raw)
{
    rw_spindle_reading r = { position_raw, 0u, 0u, false };
    return r;
}

/* The bus side until idle; reads answer with *r (NULL: reply lost). Returns the jobs done. */
static unsigned serve(const rw_spindle_reading *r)
{
    unsigned jobs = 0u;
    for (;;) {
        rw_spindle_job job = rw_spindle_exchange_next_job(&ex);
        if (job.kind == RW_SPINDLE_JOB_NONE) {
            return jobs;
        }
        if (job.kind == RW_SPINDLE_JOB_WRITE) {
            rw_spindle_exchange_write_done(&ex, &job, true);
        } else {
            rw_spindle_exchange_read_done(&ex, &job, r);
        }
        ++jobs;
        TEST_ASSERT_LESS_THAN(10u, jobs);
    }
}

static void test_reading_arrives_at_the_next_step_once(void)
{
    rw_spindle_reading out;
    TEST_ASSERT_FALSE(rw_spindle_exchange_take(&ex, &out));
    rw_spindle_exchange_post(&ex, 200u);
    rw_spindle_job first = rw_spindle_exchange_next_job(&ex);
    TEST_ASSERT_EQUAL(RW_SPINDLE_JOB_WRITE, first.kind);
    TEST_ASSERT_EQUAL_UINT16(200u, first.moving_speed_raw);
    const rw_spindle_reading r = reading_at(321u);
    TEST_ASSERT_EQUAL_UINT(2u, serve(&r));
    TEST_ASSERT_TRUE(rw_spindle_exchange_take(&ex, &out));
    TEST_ASSERT_EQUAL_UINT16(321u, out.position_raw);
    TEST_ASSERT_FALSE(rw_spindle_exchange_take(&ex, &out));
    TEST_ASSERT_EQUAL_UINT32(1u, ex.counters.taken);
    TEST_ASSERT_EQUAL_UINT32(2u, ex.counters.missing);
}

static void test_lost_reply_is_a_step_without_reading(void)
{
    rw_spindle_reading out;
    (void)rw_spindle_exchange_take(&ex, &out);
    TEST_ASSERT_EQUAL_UINT(1u, serve(NULL));
    TEST_ASSERT_FALSE(rw_spindle_exchange_take(&ex, &out));
    const rw_spindle_reading r = reading_at(99u);
    (void)serve(&r);
    TEST_ASSERT_TRUE(rw_spindle_exchange_take(&ex, &out));
    TEST_ASSERT_EQUAL_UINT16(99u, out.position_raw);
    TEST_ASSERT_EQUAL_UINT32(1u, ex.counters.reads_failed);
    TEST_ASSERT_EQUAL_UINT32(1u, ex.counters.reads_ok);
}

static void test_only_the_latest_post_is_written(void)
{
    rw_spindle_exchange_post(&ex, 1u);
    rw_spindle_exchange_post(&ex, 2u);
    rw_spindle_exchange_post(&ex, 1027u);
    rw_spindle_job job = rw_spindle_exchange_next_job(&ex);
    TEST_ASSERT_EQUAL(RW_SPINDLE_JOB_WRITE, job.kind);
    TEST_ASSERT_EQUAL_UINT16(1027u, job.moving_speed_raw);
    rw_spindle_exchange_write_done(&ex, &job, false);
    TEST_ASSERT_EQUAL(RW_SPINDLE_JOB_NONE, rw_spindle_exchange_next_job(&ex).kind);
    TEST_ASSERT_EQUAL_UINT32(1u, ex.counters.writes_failed);
}

static void test_late_bus_serves_the_latest_request_once(void)
{
    rw_spindle_reading out;
    for (int i = 0; i < 3; ++i) {
        TEST_ASSERT_FALSE(rw_spindle_exchange_take(&ex, &out));
    }
    const rw_spindle_reading r = reading_at(7u);
    TEST_ASSERT_EQUAL_UINT(1u, serve(&r));
    TEST_ASSERT_EQUAL_UINT32(2u, ex.counters.late);
}

static void test_tick_between_job_and_result(void)
{
    rw_spindle_reading out;
    (void)rw_spindle_exchange_take(&ex, &out);
    rw_spindle_job job = rw_spindle_exchange_next_job(&ex);
    TEST_ASSERT_EQUAL(RW_SPINDLE_JOB_READ, job.kind);
    TEST_ASSERT_FALSE(rw_spindle_exchange_take(&ex, &out)); /* the tick interrupts the read */
    rw_spindle_exchange_post(&ex, 55u);
    const rw_spindle_reading r = reading_at(123u);
    rw_spindle_exchange_read_done(&ex, &job, &r);
    TEST_ASSERT_TRUE(rw_spindle_exchange_take(&ex, &out));
    TEST_ASSERT_EQUAL_UINT16(123u, out.position_raw);
    TEST_ASSERT_EQUAL(RW_SPINDLE_JOB_WRITE, rw_spindle_exchange_next_job(&ex).kind);
}

static void test_hal_calls_are_the_tick_side(void)
{
    rw_hal_spindle hal = rw_spindle_exchange_hal(&ex);
    rw_spindle_reading out;
    TEST_ASSERT_FALSE(hal.read(hal.ctx, &out));
    hal.write_moving_speed_raw(hal.ctx, 1500u);
    rw_spindle_job job = rw_spindle_exchange_next_job(&ex);
    TEST_ASSERT_EQUAL_UINT16(1500u, job.moving_speed_raw);
}

int main(void)
{
    UNITY_BEGIN();
    RUN_TEST(test_reading_arrives_at_the_next_step_once);
    RUN_TEST(test_lost_reply_is_a_step_without_reading);
    RUN_TEST(test_only_the_latest_post_is_written);
    RUN_TEST(test_late_bus_serves_the_latest_request_once);
    RUN_TEST(test_tick_between_job_and_result);
    RUN_TEST(test_hal_calls_are_the_tick_side);
    return UNITY_END();
}
