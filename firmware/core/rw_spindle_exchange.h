/* Split spindle transaction: the AX-12A's read and write handed between the control tick and the bus side,
 * so that the tick never waits for the servo.
 *
 * Tick side (behind rw_hal_spindle: read, then write_moving_speed_raw, once per spindle step):
 *   rw_spindle_exchange_take   the reading the bus side completed since the previous take (false when there
 *                              is none: the reply was lost, timed out, or the bus side has not reached the
 *                              request yet), and a request for the next one;
 *   rw_spindle_exchange_post   the moving speed to write.
 * So a reading is one spindle period old when the core steps with it (10 ms on the board), and an
 * unanswered request is simply a step without a reading (the core's dead reckoning; NO_ANSWER only after
 * spindle_timeout_s).
 * Bus side (the board's background loop; the SIL's bus model):
 *   rw_spindle_exchange_next_job   what to do now: the latest posted write first, then the latest read
 *                                  request, else nothing (older posts and requests are superseded);
 *   rw_spindle_exchange_write_done / _read_done   the outcome of that job (a reading, or NULL: no reply).
 *
 * Concurrency: one tick side and one bus side, single core. The tick side runs to completion without the
 * bus side running (an interrupt over the background loop on the board; a call between bus steps in SIL);
 * the bus side may be interrupted by the tick anywhere. Every shared word is written by one side only, and
 * the reading is published before the sequence number that announces it (a compiler barrier between), so
 * the tick never takes a half-written reading. Pure: no clock, no heap, no I/O. */
#ifndef RW_SPINDLE_EXCHANGE_H
#define RW_SPINDLE_EXCHANGE_H

#include <stdbool.h>
#include <stdint.h>

#include "rw_hal_spindle.h"

typedef enum {
    RW_SPINDLE_JOB_NONE = 0,
    RW_SPINDLE_JOB_WRITE = 1, /* write moving_speed_raw to register 32 */
    RW_SPINDLE_JOB_READ = 2,  /* read registers 36-41 */
} rw_spindle_job_kind;

typedef struct rw_spindle_job {
    uint8_t kind;              /* rw_spindle_job_kind */
    uint16_t moving_speed_raw; /* RW_SPINDLE_JOB_WRITE: the value to write */
    uint32_t seq;              /* the post or request this job serves (hand it back to *_done) */
} rw_spindle_job;

/* Counters, each written by one side (named by it). */
typedef struct rw_spindle_exchange_counters {
    uint32_t requests;       /* tick: read requests */
    uint32_t taken;          /* tick: fresh readings handed to the core */
    uint32_t missing;        /* tick: steps without a fresh reading (no reply, or the bus side late) */
    uint32_t late;           /* tick: requests made while the previous one was still unserved */
    uint32_t reads_ok;       /* bus: readings published */
    uint32_t reads_failed;   /* bus: reads without a valid reply (timeout, lost or corrupted reply) */
    uint32_t writes_ok;      /* bus: writes answered by a valid status packet */
    uint32_t writes_failed;  /* bus: writes without one */
} rw_spindle_exchange_counters;

typedef struct rw_spindle_exchange {
    /* written by the tick side */
    volatile uint32_t post_seq;     /* bumped by each post, after post_raw */
    volatile uint16_t post_raw;
    volatile uint32_t request_seq;  /* bumped by each take */
    uint32_t taken_reading_seq;     /* reading_seq at the previous take */
    /* written by the bus side */
    volatile uint32_t written_seq;  /* post_seq of the last write done (ok or not) */
    volatile uint32_t served_seq;   /* request_seq of the last read done (ok or not) */
    volatile uint32_t reading_seq;  /* bumped after each reading is published */
    rw_spindle_reading reading;     /* the latest published reading */
    rw_spindle_exchange_counters counters;
} rw_spindle_exchange;

#ifdef __cplusplus
extern "C" {
#endif

void rw_spindle_exchange_init(rw_spindle_exchange *ex);

/* Tick side. */
bool rw_spindle_exchange_take(rw_spindle_exchange *ex, rw_spindle_reading *out);
void rw_spindle_exchange_post(rw_spindle_exchange *ex, uint16_t moving_speed_raw);

/* Bus side. */
rw_spindle_job rw_spindle_exchange_next_job(const rw_spindle_exchange *ex);
void rw_spindle_exchange_write_done(rw_spindle_exchange *ex, const rw_spindle_job *job, bool answered);
/* reading: the reply's registers, or NULL when no valid reply came. */
void rw_spindle_exchange_read_done(rw_spindle_exchange *ex, const rw_spindle_job *job, const rw_spindle_reading *reading);

/* rw_hal_spindle over an exchange: the tick side's calls (ctx = the exchange). */
rw_hal_spindle rw_spindle_exchange_hal(rw_spindle_exchange *ex);

#ifdef __cplusplus
}
#endif

#endif /* RW_SPINDLE_EXCHANGE_H */
