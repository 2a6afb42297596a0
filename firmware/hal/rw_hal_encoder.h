/* Rope-drive encoder: cumulative edge count and the capture time of the latest edge (M/T estimation). */
#ifndef RW_HAL_ENCODER_H
#define RW_HAL_ENCODER_H

#include <stdint.h>

typedef struct rw_encoder_sample {
    uint32_t counts;       /* cumulative edges since boot (wraps) */
    uint32_t last_edge_us; /* time of the latest edge on the tick clock, microseconds (wraps) */
} rw_encoder_sample;

typedef struct rw_hal_encoder {
    void *ctx;
    rw_encoder_sample (*read)(void *ctx);
} rw_hal_encoder;

#endif /* RW_HAL_ENCODER_H */
