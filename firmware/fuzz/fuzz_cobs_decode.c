/* Fuzz target: the COBS decoder of the USB serial link, on arbitrary bytes.
 *
 * The first input byte picks the output capacity (0..255), the rest is the encoded frame; both live in
 * exactly sized heap buffers, so AddressSanitizer reports any read past n or write past cap.
 * Invariants (a violation traps):
 *   - rw_cobs_decode never returns more than cap, and never more than n;
 *   - a successful decode re-encodes to bytes with no zero in them, which decode back to the same data;
 *   - any input, encoded, has no zero byte, fits RW_COBS_MAX_ENCODED and decodes back to itself. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_common.h"
#include "rw_cobs.h"

static void check_round_trip(const uint8_t *data, size_t n)
{
    size_t enc_cap = RW_COBS_MAX_ENCODED(n);
    uint8_t *enc = malloc(enc_cap);
    RW_FUZZ_REQUIRE(enc != NULL);
    size_t e = rw_cobs_encode(data, n, enc, enc_cap);
    RW_FUZZ_REQUIRE(e >= 1u && e <= enc_cap);
    RW_FUZZ_REQUIRE(memchr(enc, 0, e) == NULL);
    RW_FUZZ_REQUIRE(rw_cobs_encode(data, n, enc, enc_cap - 1u) == 0u); /* one byte short: refused */
    uint8_t *dec = malloc(n == 0u ? 1u : n);
    RW_FUZZ_REQUIRE(dec != NULL);
    size_t d = rw_cobs_decode(enc, e, dec, n);
    RW_FUZZ_REQUIRE(d == n && (n == 0u || memcmp(dec, data, n) == 0));
    free(dec);
    free(enc);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0u) {
        return 0;
    }
    size_t cap = data[0];
    size_t n = size - 1u;
    uint8_t *in = rw_fuzz_exact_copy(data + 1, n);
    uint8_t *out = malloc(cap == 0u ? 1u : cap);
    RW_FUZZ_REQUIRE(out != NULL);
    size_t d = rw_cobs_decode(in, n, out, cap);
    RW_FUZZ_REQUIRE(d <= cap && d <= n);
    if (d > 0u) {
        check_round_trip(out, d);
    }
    check_round_trip(in, n);
    free(out);
    free(in);
    return 0;
}
