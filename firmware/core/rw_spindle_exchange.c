#include "rw_spindle_exchange.h"

#include <string.h>

/* Keeps the compiler from moving memory accesses across it (single core: ordering against an interrupt). */
#define RW_COMPILER_BARRIER() __asm__ __volatile__("" ::: "memory")

void rw_spindle_exchange_init(rw_spindle_exchange *ex)
{
    memset(ex, 0, sizeof *ex);
}

bool rw_spindle_exchange_take(rw_spindle_exchange *ex, rw_spindle_reading *out)
{
    const uint32_t published = ex->reading_seq;
    RW_COMPILER_BARRIER();
    const bool fresh = published != ex->taken_reading_seq;
    if (fresh) {
        *out = ex->reading;
        ex->taken_reading_seq = published;
        ++ex->counters.taken;
    } else {
        ++ex->counters.missing;
    }
    if (ex->served_seq != ex->request_seq) {
        ++ex->counters.late; /* the previous request is still unserved: this one supersedes it */
    }
    ex->request_seq = ex->request_seq + 1u;
    ++ex->counters.requests;
    return fresh;
}

void rw_spindle_exchange_post(rw_spindle_exchange *ex, uint16_t moving_speed_raw)
{
    ex->post_raw = moving_speed_raw;
    RW_COMPILER_BARRIER();
    ex->post_seq = ex->post_seq + 1u;
}

rw_spindle_job rw_spindle_exchange_next_job(const rw_spindle_exchange *ex)
{
    rw_spindle_job job = { RW_SPINDLE_JOB_NONE, 0u, 0u };
    const uint32_t post = ex->post_seq;
    RW_COMPILER_BARRIER();
    if (post != ex->written_seq) {
        job.kind = RW_SPINDLE_JOB_WRITE;
        /* a tick between the two loads posts a newer value with a newer seq: this job writes the newer
         * value, and the next one writes it again (harmless) */
        job.moving_speed_raw = ex->post_raw;
        job.seq = post;
        return job;
    }
    const uint32_t request = ex->request_seq;
    if (request != ex->served_seq) {
        job.kind = RW_SPINDLE_JOB_READ;
        job.seq = request;
    }
    return job;
}

void rw_spindle_exchange_write_done(rw_spindle_exchange *ex, const rw_spindle_job *job, bool answered)
{
    if (job->kind != RW_SPINDLE_JOB_WRITE) {
        return;
    }
    if (answered) {
        ++ex->counters.writes_ok;
    } else {
        ++ex->counters.writes_failed;
    }
    ex->written_seq = job->seq;
}

void rw_spindle_exchange_read_done(rw_spindle_exchange *ex, const rw_spindle_job *job, const rw_spindle_reading *reading)
{
    if (job->kind != RW_SPINDLE_JOB_READ) {
        return;
    }
    if (reading != NULL) {
        ex->reading = *reading;
        RW_COMPILER_BARRIER();
        ex->reading_seq = ex->reading_seq + 1u;
        ++ex->counters.reads_ok;
    } else {
        ++ex->counters.reads_failed;
    }
    ex->served_seq = job->seq;
}

static bool hal_read(void *ctx, rw_spindle_reading *out)
{
    return rw_spindle_exchange_take((rw_spindle_exchange *)ctx, out);
}

static void hal_write(void *ctx, uint16_t raw)
{
    rw_spindle_exchange_post((rw_spindle_exchange *)ctx, raw);
}

rw_hal_spindle rw_spindle_exchange_hal(rw_spindle_exchange *ex)
{
    rw_hal_spindle hal = { ex, hal_read, hal_write };
    return hal;
}
