/* Control-tick scheduler facts the core reports (the tick itself is driven from outside the core). */
#ifndef RW_HAL_SCHEDULER_H
#define RW_HAL_SCHEDULER_H

#include <stdint.h>

typedef struct rw_hal_scheduler {
    void *ctx;
    uint32_t (*tick_overruns)(void *ctx); /* ticks that started late or ran past their period, since boot */
} rw_hal_scheduler;

#endif /* RW_HAL_SCHEDULER_H */
