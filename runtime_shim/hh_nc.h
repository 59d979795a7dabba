/* hh_nc.h - the NC model of the simulation (spec 12.2, 12.3, 12.5, 12.6, 17b.6-9; ASSUMPTION A-39).
 *
 * Scenario `nc` actions are put into ONE queue and played strictly one at a time: an
 * action starts only when the previous one has completed (its strobe reset by the NC and
 * its acknowledgement reset by the PLC).  The model acts only in phase 1 of a PLC cycle
 * (hh_nc_phase); it reads the PLC's acknowledgement markers through a callback and returns
 * the operand writes the caller must apply before the PLC program runs.
 *
 * Profiles: HH_NC_PROFILE_ITNC (itnc530, tnc426, tv) uses the interface table of spec 12.2.
 * HH_NC_PROFILE_TNC407 knows only the M function (code W260, strobe M2045, ack M2482); every
 * other action is rejected by its enqueue function with HH_NC_EUNSUPPORTED, and the model
 * writes neither a first-cycle marker (unknown on the TNC 407, Q-04) nor W272 (not an
 * interface word of that profile, so it may be an ordinary program word there).
 *
 * Which writes a phase produces (every write of a phase names a distinct operand; when two
 * steps of one phase write the same operand, the later value replaces the earlier):
 *  - cycle 0 (ITNC profile): M4172 = 1 and W272 = current operating mode (default 1);
 *    cycle 1: M4172 = 0 (M4172 or the marker given to hh_nc_set_first_cycle_marker, A-38).
 *    W272 is otherwise written only when a `mode` action plays (17b.9).
 *  - when an action starts: its code words, its additional markers (TOOL CALL: M4521-M4523,
 *    exactly one set) and its strobe = 1.  Code words and the TOOL CALL markers are written
 *    only then and are never re-asserted: they keep their value until the next action that
 *    writes them, whatever the PLC does with them.
 *  - strobe markers are NC-owned (A-58: a PLC write may be overwritten in phase 1): while a
 *    handshake is in progress the strobe is re-asserted in every phase with the NC's value
 *    (1 while waiting for the acknowledgement, 0 while waiting for its reset).  After the
 *    handshake completed it is not written again.
 *  - `restart`: M4173 (program) / M4174 (machine parameters) = 1 in the phase the action
 *    plays and = 0 in the next phase (one cycle), no handshake.
 *  - `mode`: W272 = m when the action plays, no handshake.
 *
 * Timeout (17b.8): a handshake whose strobe was set in cycle c and that has not completed
 * (acknowledged AND acknowledgement reset) fails in the first cycle k with
 * (k - c) * cycle_time_ms > HH_NC_TIMEOUT_MS.  The whole handshake is timed, not only the
 * wait for the acknowledgement: 17b.6 defines completion as "strobe reset and
 * acknowledgement reset", and a PLC that never resets its acknowledgement would otherwise
 * stall the queue silently.  The error is sticky: every later phase returns it again.
 * An action whose acknowledgement marker the PLC still holds at 1 when its turn comes does
 * not start (spec 12.3: "ack == 0") and, its strobe never having been set, cannot time out;
 * it stays pending (hh_nc_pending), which the run report should show.
 */
#ifndef HH_NC_H
#define HH_NC_H

#include "hh_common.h"

typedef struct hh_nc hh_nc;

enum { HH_NC_PROFILE_ITNC = 0, HH_NC_PROFILE_TNC407 = 1 };

/* hh_nc_state */
enum { HH_NC_IDLE = 0, HH_NC_WAIT_ACK = 1, HH_NC_WAIT_ACK_RESET = 2 };

/* enqueue results */
enum {
    HH_NC_OK = 0,
    HH_NC_EUNSUPPORTED = -1, /* the profile has no such NC function */
    HH_NC_ERANGE = -2,       /* a value does not fit its code operand (W: -32768..32767) or bad kind */
    HH_NC_ENOMEM = -3
};

/* hh_nc_phase results other than a write count */
enum {
    HH_NC_PHASE_TIMEOUT = -1,   /* handshake timeout: see hh_nc_error */
    HH_NC_PHASE_OVERFLOW = -2,  /* max_out too small (HH_NC_MAX_WRITES always suffices); nothing changed */
    HH_NC_PHASE_SEQUENCE = -3   /* cycles must be 0, 1, 2, ... in this order; nothing changed */
};

enum { HH_NC_RESTART_PROGRAM = 0, HH_NC_RESTART_MACHINE_PARAMETERS = 1 };

#define HH_NC_TIMEOUT_MS 10000
#define HH_NC_MAX_WRITES 32

/* NULL when cycle_time_ms <= 0, the profile is unknown or memory is exhausted. */
hh_nc *hh_nc_new(int32_t cycle_time_ms, int32_t profile);
void hh_nc_free(hh_nc *nc);
/* ASSUMPTION A-38 first_cycle_marker: the marker the ITNC profile pulses in cycles 0/1 instead
 * of M4172 (the TNC 407 writes none).  HH_NC_OK, or HH_NC_ERANGE for a negative marker. */
int hh_nc_set_first_cycle_marker(hh_nc *nc, int32_t marker);

/* Enqueue one scenario action; HH_NC_OK or a negative HH_NC_E... code (nothing queued then). */
int hh_nc_m_function(hh_nc *nc, int32_t code);            /* W260; M4072/M4092 (tnc407: M2045/M2482) */
int hh_nc_spindle_speed(hh_nc *nc, int32_t speed);        /* D356; M4071/M4091 */
int hh_nc_gear(hh_nc *nc, int32_t gear);                  /* W256; M4070/M4090 */
/* W264 = tool, W262 = pocket, M4521 (tool 0) / M4522 (pocket >= 1) / M4523 (otherwise);
 * M4073/M4093.  second_strobe != 0: a second handshake on M4520 follows, see hh_nc.c. */
int hh_nc_tool_call(hh_nc *nc, int32_t tool, int32_t pocket, int32_t second_strobe);
int hh_nc_tool_def(hh_nc *nc, int32_t tool, int32_t pocket); /* W264/W262; M4074/M4094 */
int hh_nc_fn19(hh_nc *nc, int32_t value1, int32_t value2);   /* D280/D284; M4075/M4095 */
int hh_nc_mode(hh_nc *nc, int32_t mode);                     /* W272, no handshake */
int hh_nc_restart(hh_nc *nc, int32_t kind);                  /* HH_NC_RESTART_...: M4173 / M4174 */

/* Phase 1 of PLC cycle `cycle` (read_bit must not be NULL; it is called only while actions are
 * pending, at most a few times per phase).  Returns the number of writes stored in out[0..n-1]
 * (apply them in this order) or a negative HH_NC_PHASE_... code. */
int hh_nc_phase(hh_nc *nc, int64_t cycle, hh_read_bit read_bit, void *ctx, hh_write *out, int max_out);

/* Actions queued and not yet completed, including the one whose handshake is in progress. */
int32_t hh_nc_pending(const hh_nc *nc);
int32_t hh_nc_state(const hh_nc *nc);
/* Scenario name of the action in progress ("m_function", "tool_call", ...), NULL when idle. */
const char *hh_nc_active_function(const hh_nc *nc);
/* NULL when no timeout happened; otherwise the scenario name of the failing action and
 * *cycle = the cycle the timeout was reported for (cycle may be NULL). */
const char *hh_nc_error(const hh_nc *nc, int64_t *cycle);
/* Details of the timeout: the cycle its strobe was set, the strobe and the ack marker.
 * Returns 0 when there is no error (outputs untouched), 1 otherwise.  NULL outputs are skipped. */
int hh_nc_error_detail(const hh_nc *nc, int64_t *started, int32_t *strobe, int32_t *ack);

#endif
