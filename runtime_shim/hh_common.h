/* hh_common.h - types shared by the NC model and the module table of the hh2iec runtime shim.
 *
 * The shim is the simulated environment that both sides of the co-simulation share: the
 * Python reference interpreter calls it through ctypes, the matiec-compiled ST links it.
 * It never touches PLC memory itself; it reports operand writes and the caller applies
 * them (the caller owns the byte order of W/D, spec 5.2).
 */
#ifndef HH_COMMON_H
#define HH_COMMON_H

#include <stdint.h>

/* One operand write produced by the shim: kind 'M' (marker), 'T' (timer), 'W' (16-bit
 * word; value already sign-extended from 16 bits, i.e. what a later `L W` reads back) or
 * 'D' (32-bit double word). addr is the operand number (M4072 -> 4072, W260 -> 260). */
typedef struct {
    char kind;
    int32_t addr;
    int32_t value;
} hh_write;

/* Reads the current value (0/1) of marker M<marker> in the PLC's memory; ctx is passed through. */
typedef int32_t (*hh_read_bit)(void *ctx, int32_t marker);

#define HH_SHIM_VERSION 1

#endif
