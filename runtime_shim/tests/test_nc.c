/* test_nc.c - unit tests of the NC model (spec 12.3, 17b.6-9, TV-56, TV-58). */
#include <string.h>

#include "hh_nc.h"
#include "hh_test.h"

/* A toy PLC memory: W and D are kept apart by address, enough for the interface operands. */
typedef struct {
    int32_t M[10000];
    int32_t W[2048];
    int32_t D[2048];
    hh_write last[HH_NC_MAX_WRITES]; /* writes of the last phase */
    int n_last;
} plc;

static plc mem;

static int32_t read_marker(void *ctx, int32_t m) { return ((plc *)ctx)->M[m]; }

static void reset_plc(void) { memset(&mem, 0, sizeof mem); }

/* Phase 1 of `cycle`, applying the writes to mem; returns the hh_nc_phase result. */
static int phase(hh_nc *nc, int64_t cycle)
{
    int i, n = hh_nc_phase(nc, cycle, read_marker, &mem, mem.last, HH_NC_MAX_WRITES);
    mem.n_last = n > 0 ? n : 0;
    for (i = 0; i < mem.n_last; i++) {
        const hh_write *w = &mem.last[i];
        if (w->kind == 'M')
            mem.M[w->addr] = w->value;
        else if (w->kind == 'W')
            mem.W[w->addr] = w->value;
        else
            mem.D[w->addr] = w->value;
    }
    return n;
}

/* How often the last phase wrote operand kind/addr, and the value written. */
static int written(char kind, int32_t addr, int32_t *value)
{
    int i, count = 0;
    for (i = 0; i < mem.n_last; i++) {
        if (mem.last[i].kind == kind && mem.last[i].addr == addr) {
            count++;
            if (value != NULL)
                *value = mem.last[i].value;
        }
    }
    return count;
}

/* A PLC that acknowledges a strobe in the cycle it sees it and resets the ack with the strobe. */
static void plc_echo(int32_t strobe, int32_t ack) { mem.M[ack] = mem.M[strobe]; }

static void tv56_m_function_handshake(void)
{
    static const int32_t strobe[3] = {1, 0, 0}, ack[3] = {1, 0, 0}, code[3] = {3, 3, 3};
    hh_nc *nc = hh_nc_new(20, HH_NC_PROFILE_ITNC);
    int64_t c;
    int o5 = 0;
    reset_plc();
    CHECK_EQ(hh_nc_m_function(nc, 3), HH_NC_OK);
    for (c = 0; c < 3; c++) {
        CHECK(phase(nc, c) >= 0);
        /* the program of TV-56 */
        if (mem.M[4072] && mem.W[260] == 3)
            o5 = 1;
        mem.M[4092] = mem.M[4072];
        CHECK_EQ(mem.M[4072], strobe[c]);
        CHECK_EQ(mem.M[4092], ack[c]);
        CHECK_EQ(mem.W[260], code[c]);
        CHECK_EQ(o5, 1);
    }
    CHECK_EQ(hh_nc_pending(nc), 0);
    CHECK_EQ(hh_nc_state(nc), HH_NC_IDLE);
    hh_nc_free(nc);
}

static void tv58_tool_call(void)
{
    hh_nc *nc = hh_nc_new(20, HH_NC_PROFILE_ITNC);
    int m30[2], w100[2], c;
    reset_plc();
    CHECK_EQ(hh_nc_tool_call(nc, 5, 2, 0), HH_NC_OK);
    for (c = 0; c < 2; c++) {
        CHECK(phase(nc, c) >= 0);
        m30[c] = mem.M[4073] && mem.M[4522];
        w100[c] = mem.M[4073] ? mem.W[264] : (c ? w100[c - 1] : 0);
        mem.M[4093] = mem.M[4073];
        CHECK_EQ(mem.W[262], 2);
    }
    CHECK_EQ(m30[0], 1);
    CHECK_EQ(m30[1], 0);
    CHECK_EQ(w100[0], 5);
    CHECK_EQ(w100[1], 5);
    hh_nc_free(nc);
}

/* 17b.6: the second action starts only after strobe AND ack of the first are reset. */
static void queue_plays_one_at_a_time(void)
{
    hh_nc *nc = hh_nc_new(20, HH_NC_PROFILE_ITNC);
    static const int32_t m_strobe[5] = {1, 0, 0, 0, 0}, s_strobe[5] = {0, 0, 1, 0, 0};
    static const int32_t pending[5] = {2, 2, 1, 1, 0};
    int c;
    reset_plc();
    CHECK_EQ(hh_nc_m_function(nc, 3), HH_NC_OK);
    CHECK_EQ(hh_nc_spindle_speed(nc, 1500), HH_NC_OK);
    CHECK_EQ(hh_nc_pending(nc), 2);
    for (c = 0; c < 5; c++) {
        CHECK(phase(nc, c) >= 0);
        CHECK_EQ(mem.M[4072], m_strobe[c]);
        CHECK_EQ(mem.M[4071], s_strobe[c]);
        CHECK_EQ(mem.D[356], c >= 2 ? 1500 : 0);
        plc_echo(4072, 4092);
        plc_echo(4071, 4091);
        CHECK_EQ(hh_nc_pending(nc), pending[c]);
    }
    hh_nc_free(nc);
}

static void tool_call_marker_selection(void)
{
    static const int32_t cases[5][3] = {{0, 5, 4521}, {5, 1, 4522}, {5, 2, 4522}, {5, -1, 4523}, {5, 0, 4523}};
    int i;
    for (i = 0; i < 5; i++) {
        hh_nc *nc = hh_nc_new(20, HH_NC_PROFILE_ITNC);
        int32_t m, v;
        reset_plc();
        mem.M[4521] = mem.M[4522] = mem.M[4523] = 1; /* left over: must be reset */
        CHECK_EQ(hh_nc_tool_call(nc, cases[i][0], cases[i][1], 0), HH_NC_OK);
        CHECK(phase(nc, 0) >= 0);
        for (m = 4521; m <= 4523; m++) {
            CHECK_EQ(written('M', m, &v), 1);
            CHECK_EQ(mem.M[m], m == cases[i][2]);
        }
        CHECK_EQ(mem.W[264], cases[i][0]);
        CHECK_EQ(mem.W[262], cases[i][1]);
        CHECK_EQ(mem.M[4073], 1);
        /* the markers and words stay after the handshake (17b.7, A-39) */
        plc_echo(4073, 4093);
        CHECK(phase(nc, 1) >= 0);
        CHECK_EQ(written('W', 264, NULL) + written('W', 262, NULL) + written('M', cases[i][2], NULL), 0);
        plc_echo(4073, 4093);
        CHECK(phase(nc, 2) >= 0);
        CHECK_EQ(mem.M[cases[i][2]], 1);
        CHECK_EQ(hh_nc_pending(nc), 0);
        hh_nc_free(nc);
    }
}

static void tool_call_second_strobe(void)
{
    static const int32_t first[7] = {1, 0, 0, 0, 0, 0, 0}, second[7] = {0, 0, 1, 0, 0, 0, 0};
    hh_nc *nc = hh_nc_new(20, HH_NC_PROFILE_ITNC);
    int c;
    reset_plc();
    CHECK_EQ(hh_nc_tool_call(nc, 7, 3, 1), HH_NC_OK);
    CHECK_EQ(hh_nc_gear(nc, 2), HH_NC_OK);
    for (c = 0; c < 7; c++) {
        CHECK(phase(nc, c) >= 0);
        CHECK_EQ(mem.M[4073], first[c]);
        CHECK_EQ(mem.M[4520], second[c]);
        CHECK_EQ(mem.M[4070], c == 4); /* the gear action starts once the second handshake completed */
        mem.M[4093] = mem.M[4073] | mem.M[4520];
        plc_echo(4070, 4090);
    }
    CHECK_EQ(mem.W[256], 2);
    CHECK_EQ(hh_nc_pending(nc), 0);
    hh_nc_free(nc);
}

/* 17b.8: started in cycle c, fails in the first cycle k with (k - c) * cycle_time > 10 s. */
static void check_timeout(int32_t cycle_time, int64_t start, int64_t expected, int ack_but_never_reset)
{
    hh_nc *nc = hh_nc_new(cycle_time, HH_NC_PROFILE_ITNC);
    int64_t c, when = -1, started = -1;
    int32_t strobe = 0, ack = 0;
    int rc = 0;
    reset_plc();
    for (c = 0; c <= expected + 1; c++) {
        if (c == start)
            CHECK_EQ(hh_nc_fn19(nc, 11, -12), HH_NC_OK);
        rc = phase(nc, c);
        if (c < expected)
            CHECK(rc >= 0);
        else
            CHECK_EQ(rc, HH_NC_PHASE_TIMEOUT);
        if (ack_but_never_reset)
            mem.M[4095] |= mem.M[4075];
    }
    CHECK(hh_nc_error(nc, &when) != NULL && strcmp(hh_nc_error(nc, &when), "fn19") == 0);
    CHECK_EQ(when, expected);
    CHECK_EQ(hh_nc_error_detail(nc, &started, &strobe, &ack), 1);
    CHECK_EQ(started, start);
    CHECK_EQ(strobe, 4075);
    CHECK_EQ(ack, 4095);
    CHECK_EQ(mem.D[280], 11);
    CHECK_EQ(mem.D[284], -12);
    hh_nc_free(nc);
}

static void handshake_timeout(void)
{
    check_timeout(20, 0, 501, 0);
    check_timeout(20, 3, 504, 0);
    check_timeout(30, 0, 334, 0);
    check_timeout(20, 0, 501, 1);
}

static void no_error_without_timeout(void)
{
    hh_nc *nc = hh_nc_new(20, HH_NC_PROFILE_ITNC);
    int64_t when = -7;
    CHECK(hh_nc_error(nc, &when) == NULL);
    CHECK_EQ(when, -7);
    CHECK_EQ(hh_nc_error_detail(nc, NULL, NULL, NULL), 0);
    hh_nc_free(nc);
}

static void first_cycle_marker_and_mode_word(void)
{
    hh_nc *nc = hh_nc_new(20, HH_NC_PROFILE_ITNC);
    int32_t v = -1;
    reset_plc();
    CHECK_EQ(phase(nc, 0), 2);
    CHECK_EQ(written('M', 4172, &v), 1);
    CHECK_EQ(v, 1);
    CHECK_EQ(written('W', 272, &v), 1);
    CHECK_EQ(v, 1);
    CHECK_EQ(phase(nc, 1), 1);
    CHECK_EQ(written('M', 4172, &v), 1);
    CHECK_EQ(v, 0);
    CHECK_EQ(phase(nc, 2), 0);
    hh_nc_free(nc);

    nc = hh_nc_new(20, HH_NC_PROFILE_ITNC); /* another first-cycle marker replaces M4172 */
    CHECK_EQ(hh_nc_set_first_cycle_marker(nc, -1), HH_NC_ERANGE);
    CHECK_EQ(hh_nc_set_first_cycle_marker(nc, 4171), HH_NC_OK);
    CHECK_EQ(phase(nc, 0), 2);
    CHECK_EQ(written('M', 4172, NULL), 0);
    CHECK_EQ(written('M', 4171, &v), 1);
    CHECK_EQ(v, 1);
    CHECK_EQ(phase(nc, 1), 1);
    CHECK_EQ(written('M', 4171, &v), 1);
    CHECK_EQ(v, 0);
    hh_nc_free(nc);

    nc = hh_nc_new(20, HH_NC_PROFILE_TNC407); /* first-cycle marker unknown, no W272 */
    CHECK_EQ(phase(nc, 0), 0);
    CHECK_EQ(phase(nc, 1), 0);
    hh_nc_free(nc);
}

static void mode_and_restart(void)
{
    hh_nc *nc = hh_nc_new(20, HH_NC_PROFILE_ITNC);
    static const int32_t m4173[7] = {0, 0, 0, 1, 1, 0, 0}, m4174[7] = {0, 0, 0, 1, 0, 0, 0};
    int32_t v = -1;
    int c;
    reset_plc();
    CHECK_EQ(hh_nc_mode(nc, 5), HH_NC_OK);
    CHECK_EQ(phase(nc, 0), 2); /* M4172 and one W272 write carrying the scenario's mode */
    CHECK_EQ(written('W', 272, &v), 1);
    CHECK_EQ(v, 5);
    CHECK_EQ(hh_nc_pending(nc), 0);
    CHECK(phase(nc, 1) >= 0);
    CHECK(phase(nc, 2) >= 0);
    CHECK_EQ(written('W', 272, NULL), 0); /* not rewritten in other cycles (17b.9) */
    for (c = 3; c < 7; c++) {
        if (c == 3) {
            CHECK_EQ(hh_nc_restart(nc, HH_NC_RESTART_PROGRAM), HH_NC_OK);
            CHECK_EQ(hh_nc_restart(nc, HH_NC_RESTART_MACHINE_PARAMETERS), HH_NC_OK);
        }
        if (c == 4)
            CHECK_EQ(hh_nc_restart(nc, HH_NC_RESTART_PROGRAM), HH_NC_OK);
        CHECK(phase(nc, c) >= 0);
        CHECK_EQ(mem.M[4173], m4173[c]);
        CHECK_EQ(mem.M[4174], m4174[c]);
    }
    CHECK_EQ(mem.n_last, 0);
    hh_nc_free(nc);
}

static void mode_waits_for_the_handshake_before_it(void)
{
    hh_nc *nc = hh_nc_new(20, HH_NC_PROFILE_ITNC);
    static const int32_t w272[4] = {1, 1, 6, 6};
    int c;
    reset_plc();
    CHECK_EQ(hh_nc_m_function(nc, 30), HH_NC_OK);
    CHECK_EQ(hh_nc_mode(nc, 6), HH_NC_OK);
    for (c = 0; c < 4; c++) {
        CHECK(phase(nc, c) >= 0);
        CHECK_EQ(mem.W[272], w272[c]);
        plc_echo(4072, 4092);
    }
    hh_nc_free(nc);
}

static void held_ack_delays_start_and_strobe_is_reasserted(void)
{
    hh_nc *nc = hh_nc_new(20, HH_NC_PROFILE_ITNC);
    reset_plc();
    mem.M[4092] = 1; /* the PLC still holds the acknowledgement */
    CHECK_EQ(hh_nc_m_function(nc, 5), HH_NC_OK);
    CHECK(phase(nc, 0) >= 0);
    CHECK_EQ(mem.M[4072], 0);
    CHECK_EQ(mem.W[260], 0);
    CHECK_EQ(hh_nc_state(nc), HH_NC_IDLE);
    mem.M[4092] = 0;
    CHECK(phase(nc, 1) >= 0);
    CHECK_EQ(mem.M[4072], 1);
    CHECK_EQ(mem.W[260], 5);
    CHECK_EQ(hh_nc_state(nc), HH_NC_WAIT_ACK);
    CHECK(strcmp(hh_nc_active_function(nc), "m_function") == 0);
    mem.M[4072] = 0; /* a PLC write to the NC-owned strobe */
    mem.W[260] = 77; /* and to the code word, which the NC does not rewrite */
    CHECK(phase(nc, 2) >= 0);
    CHECK_EQ(mem.M[4072], 1);
    CHECK_EQ(mem.W[260], 77);
    hh_nc_free(nc);
}

static void tnc407_profile(void)
{
    hh_nc *nc = hh_nc_new(20, HH_NC_PROFILE_TNC407);
    reset_plc();
    CHECK_EQ(hh_nc_tool_call(nc, 1, 1, 0), HH_NC_EUNSUPPORTED);
    CHECK_EQ(hh_nc_spindle_speed(nc, 100), HH_NC_EUNSUPPORTED);
    CHECK_EQ(hh_nc_mode(nc, 2), HH_NC_EUNSUPPORTED);
    CHECK_EQ(hh_nc_restart(nc, HH_NC_RESTART_PROGRAM), HH_NC_EUNSUPPORTED);
    CHECK_EQ(hh_nc_pending(nc), 0);
    CHECK_EQ(hh_nc_m_function(nc, 8), HH_NC_OK);
    CHECK(phase(nc, 0) >= 0);
    CHECK_EQ(mem.M[2045], 1);
    CHECK_EQ(mem.M[4072], 0);
    CHECK_EQ(mem.W[260], 8);
    plc_echo(2045, 2482);
    CHECK(phase(nc, 1) >= 0);
    CHECK_EQ(mem.M[2045], 0);
    plc_echo(2045, 2482);
    CHECK(phase(nc, 2) >= 0);
    CHECK_EQ(hh_nc_pending(nc), 0);
    hh_nc_free(nc);
}

static void invalid_use(void)
{
    hh_nc *nc = hh_nc_new(20, HH_NC_PROFILE_ITNC);
    reset_plc();
    CHECK(hh_nc_new(0, HH_NC_PROFILE_ITNC) == NULL);
    CHECK(hh_nc_new(20, 2) == NULL);
    CHECK_EQ(hh_nc_m_function(nc, 32768), HH_NC_ERANGE);
    CHECK_EQ(hh_nc_m_function(nc, -32769), HH_NC_ERANGE);
    CHECK_EQ(hh_nc_tool_call(nc, 1, 40000, 0), HH_NC_ERANGE);
    CHECK_EQ(hh_nc_restart(nc, 2), HH_NC_ERANGE);
    CHECK_EQ(hh_nc_pending(nc), 0);
    CHECK_EQ(hh_nc_m_function(nc, 32767), HH_NC_OK);
    CHECK_EQ(phase(nc, 1), HH_NC_PHASE_SEQUENCE);
    CHECK(phase(nc, 0) >= 0);
    CHECK_EQ(phase(nc, 0), HH_NC_PHASE_SEQUENCE);
    CHECK_EQ(phase(nc, 2), HH_NC_PHASE_SEQUENCE);
    CHECK(phase(nc, 1) >= 0);
    /* too small an output buffer is refused and the phase can be repeated */
    CHECK_EQ(hh_nc_tool_call(nc, 2, 2, 0), HH_NC_OK);
    mem.M[4092] = 1;
    CHECK_EQ(hh_nc_phase(nc, 2, read_marker, &mem, mem.last, 0), HH_NC_PHASE_OVERFLOW);
    CHECK_EQ(hh_nc_state(nc), HH_NC_WAIT_ACK);
    CHECK_EQ(phase(nc, 2), 1); /* M4072 := 0 */
    CHECK_EQ(mem.M[4072], 0);
    mem.M[4092] = 0;
    CHECK_EQ(hh_nc_phase(nc, 3, read_marker, &mem, mem.last, 6), HH_NC_PHASE_OVERFLOW);
    CHECK_EQ(hh_nc_pending(nc), 2);
    CHECK_EQ(phase(nc, 3), 7); /* M4072 re-assert, W264, W262, M4521-M4523, M4073 */
    CHECK_EQ(hh_nc_pending(nc), 1);
    CHECK_EQ(mem.M[4073], 1);
    hh_nc_free(nc);
}

void run_nc_tests(void)
{
    RUN(tv56_m_function_handshake);
    RUN(tv58_tool_call);
    RUN(queue_plays_one_at_a_time);
    RUN(tool_call_marker_selection);
    RUN(tool_call_second_strobe);
    RUN(handshake_timeout);
    RUN(no_error_without_timeout);
    RUN(first_cycle_marker_and_mode_word);
    RUN(mode_and_restart);
    RUN(mode_waits_for_the_handshake_before_it);
    RUN(held_ack_delays_start_and_strobe_is_reasserted);
    RUN(tnc407_profile);
    RUN(invalid_use);
}
