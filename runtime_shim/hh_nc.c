/* hh_nc.c - NC model state machine of spec 12.3 with the one-queue rule of 17b.6. */
#include "hh_nc.h"

#include <stdlib.h>
#include <string.h>

typedef enum {
    K_M_FUNCTION, K_SPINDLE_SPEED, K_GEAR, K_TOOL_CALL, K_TOOL_DEF, K_FN19, K_MODE, K_RESTART
} action_kind;

/* Interface operands per action kind for the ITNC profile (spec 12.2; A-40 for the words
 * not confirmed on the iTNC).  Strobe 0 = no handshake. */
typedef struct {
    const char *name;
    int32_t strobe;
    int32_t ack;
} kind_info;

static const kind_info ITNC_KINDS[] = {
    {"m_function", 4072, 4092}, {"spindle_speed", 4071, 4091}, {"gear", 4070, 4090},
    {"tool_call", 4073, 4093},  {"tool_def", 4074, 4094},      {"fn19", 4075, 4095},
    {"mode", 0, 0},             {"restart", 0, 0},
};
static const kind_info TNC407_M_FUNCTION = {"m_function", 2045, 2482};

#define M_FIRST_CYCLE 4172
#define M_RESTART_PROGRAM 4173
#define M_RESTART_MP 4174
#define M_TOOL_CALL_SECOND_STROBE 4520
#define M_TOOL_CALL_T0 4521
#define M_TOOL_CALL_POCKET 4522
#define M_TOOL_CALL_NO_POCKET 4523
#define W_MODE 272
#define DEFAULT_MODE 1

typedef struct {
    action_kind kind;
    int32_t a, b, c;
} action;

struct hh_nc {
    int32_t cycle_time_ms;
    int32_t profile;
    action *queue;
    size_t head, len, cap;
    int32_t state;
    int stage;              /* 0: main strobe; 1: TOOL CALL second strobe (M4520) */
    int64_t started;        /* cycle the current strobe was set */
    int32_t mode;           /* last W272 value the NC wrote */
    int32_t first_cycle;    /* the first-cycle marker, M4172 unless set */
    int pulse_program;      /* M4173 was set in the previous phase: reset it now */
    int pulse_mp;
    int64_t last_cycle;     /* -1 before the first phase */
    /* timeout */
    int failed;
    const char *err_function;
    int64_t err_cycle, err_started;
    int32_t err_strobe, err_ack;
};

typedef struct {
    hh_write *w;
    int n;
    int overflow; /* more than HH_NC_MAX_WRITES distinct operands (cannot happen with the kinds above) */
} writes;

/* Later writes to an operand replace earlier ones of the same phase (see hh_nc.h). */
static void emit(writes *ws, char kind, int32_t addr, int32_t value)
{
    int i;
    for (i = 0; i < ws->n; i++) {
        if (ws->w[i].kind == kind && ws->w[i].addr == addr) {
            ws->w[i].value = value;
            return;
        }
    }
    if (ws->n == HH_NC_MAX_WRITES) {
        ws->overflow = 1;
        return;
    }
    ws->w[ws->n].kind = kind;
    ws->w[ws->n].addr = addr;
    ws->w[ws->n].value = value;
    ws->n++;
}

static int fits_word(int32_t v) { return v >= -32768 && v <= 32767; }

hh_nc *hh_nc_new(int32_t cycle_time_ms, int32_t profile)
{
    hh_nc *nc;
    if (cycle_time_ms <= 0 || (profile != HH_NC_PROFILE_ITNC && profile != HH_NC_PROFILE_TNC407))
        return NULL;
    nc = (hh_nc *)calloc(1, sizeof *nc);
    if (nc == NULL)
        return NULL;
    nc->cycle_time_ms = cycle_time_ms;
    nc->profile = profile;
    nc->state = HH_NC_IDLE;
    nc->mode = DEFAULT_MODE;
    nc->first_cycle = M_FIRST_CYCLE;
    nc->last_cycle = -1;
    return nc;
}

int hh_nc_set_first_cycle_marker(hh_nc *nc, int32_t marker)
{
    if (marker < 0)
        return HH_NC_ERANGE;
    nc->first_cycle = marker;
    return HH_NC_OK;
}

void hh_nc_free(hh_nc *nc)
{
    if (nc == NULL)
        return;
    free(nc->queue);
    free(nc);
}

static int push(hh_nc *nc, action_kind kind, int32_t a, int32_t b, int32_t c)
{
    if (nc->profile == HH_NC_PROFILE_TNC407 && kind != K_M_FUNCTION)
        return HH_NC_EUNSUPPORTED;
    if (nc->head == nc->len) /* queue drained: reuse the storage from the start */
        nc->head = nc->len = 0;
    if (nc->len == nc->cap) {
        size_t cap = nc->cap ? nc->cap * 2 : 16;
        action *q = (action *)realloc(nc->queue, cap * sizeof *q);
        if (q == NULL)
            return HH_NC_ENOMEM;
        nc->queue = q;
        nc->cap = cap;
    }
    nc->queue[nc->len].kind = kind;
    nc->queue[nc->len].a = a;
    nc->queue[nc->len].b = b;
    nc->queue[nc->len].c = c;
    nc->len++;
    return HH_NC_OK;
}

int hh_nc_m_function(hh_nc *nc, int32_t code)
{
    return fits_word(code) ? push(nc, K_M_FUNCTION, code, 0, 0) : HH_NC_ERANGE;
}

int hh_nc_spindle_speed(hh_nc *nc, int32_t speed) { return push(nc, K_SPINDLE_SPEED, speed, 0, 0); }

int hh_nc_gear(hh_nc *nc, int32_t gear)
{
    return fits_word(gear) ? push(nc, K_GEAR, gear, 0, 0) : HH_NC_ERANGE;
}

int hh_nc_tool_call(hh_nc *nc, int32_t tool, int32_t pocket, int32_t second_strobe)
{
    if (!fits_word(tool) || !fits_word(pocket))
        return HH_NC_ERANGE;
    return push(nc, K_TOOL_CALL, tool, pocket, second_strobe != 0);
}

int hh_nc_tool_def(hh_nc *nc, int32_t tool, int32_t pocket)
{
    if (!fits_word(tool) || !fits_word(pocket))
        return HH_NC_ERANGE;
    return push(nc, K_TOOL_DEF, tool, pocket, 0);
}

int hh_nc_fn19(hh_nc *nc, int32_t value1, int32_t value2) { return push(nc, K_FN19, value1, value2, 0); }

int hh_nc_mode(hh_nc *nc, int32_t mode)
{
    return fits_word(mode) ? push(nc, K_MODE, mode, 0, 0) : HH_NC_ERANGE;
}

int hh_nc_restart(hh_nc *nc, int32_t kind)
{
    if (kind != HH_NC_RESTART_PROGRAM && kind != HH_NC_RESTART_MACHINE_PARAMETERS)
        return HH_NC_ERANGE;
    return push(nc, K_RESTART, kind, 0, 0);
}

static const kind_info *info_of(const hh_nc *nc, action_kind kind)
{
    return nc->profile == HH_NC_PROFILE_TNC407 ? &TNC407_M_FUNCTION : &ITNC_KINDS[kind];
}

static const action *current(const hh_nc *nc) { return &nc->queue[nc->head]; }

static int32_t strobe_of(const hh_nc *nc)
{
    return nc->stage == 1 ? M_TOOL_CALL_SECOND_STROBE : info_of(nc, current(nc)->kind)->strobe;
}

/* Actions without a handshake complete as soon as their turn comes. */
static void play_immediate(hh_nc *nc, const action *act, writes *ws)
{
    if (act->kind == K_MODE) {
        nc->mode = act->a;
        emit(ws, 'W', W_MODE, act->a);
    } else if (act->a == HH_NC_RESTART_PROGRAM) {
        emit(ws, 'M', M_RESTART_PROGRAM, 1);
        nc->pulse_program = 1;
    } else {
        emit(ws, 'M', M_RESTART_MP, 1);
        nc->pulse_mp = 1;
    }
}

/* Code words and additional markers, written together with the strobe (spec 12.3, 17b.7). */
static void write_codes(const action *act, writes *ws)
{
    switch (act->kind) {
    case K_M_FUNCTION: emit(ws, 'W', 260, act->a); break;
    case K_SPINDLE_SPEED: emit(ws, 'D', 356, act->a); break;
    case K_GEAR: emit(ws, 'W', 256, act->a); break;
    case K_TOOL_CALL: {
        int32_t which = act->a == 0 ? M_TOOL_CALL_T0 : act->b >= 1 ? M_TOOL_CALL_POCKET : M_TOOL_CALL_NO_POCKET;
        emit(ws, 'W', 264, act->a);
        emit(ws, 'W', 262, act->b);
        emit(ws, 'M', M_TOOL_CALL_T0, which == M_TOOL_CALL_T0);
        emit(ws, 'M', M_TOOL_CALL_POCKET, which == M_TOOL_CALL_POCKET);
        emit(ws, 'M', M_TOOL_CALL_NO_POCKET, which == M_TOOL_CALL_NO_POCKET);
        break;
    }
    case K_TOOL_DEF:
        emit(ws, 'W', 264, act->a);
        emit(ws, 'W', 262, act->b);
        break;
    case K_FN19:
        emit(ws, 'D', 280, act->a);
        emit(ws, 'D', 284, act->b);
        break;
    case K_MODE:
    case K_RESTART:
        break;
    }
}

static void start_strobe(hh_nc *nc, int stage, int64_t cycle, writes *ws)
{
    nc->stage = stage;
    nc->state = HH_NC_WAIT_ACK;
    nc->started = cycle;
    emit(ws, 'M', strobe_of(nc), 1);
}

static void complete(hh_nc *nc)
{
    nc->head++;
    nc->state = HH_NC_IDLE;
    nc->stage = 0;
}

static int timed_out(const hh_nc *nc, int64_t cycle)
{
    return (cycle - nc->started) * (int64_t)nc->cycle_time_ms > HH_NC_TIMEOUT_MS;
}

static void fail(hh_nc *nc, int64_t cycle)
{
    nc->failed = 1;
    nc->err_function = info_of(nc, current(nc)->kind)->name;
    nc->err_cycle = cycle;
    nc->err_started = nc->started;
    nc->err_strobe = strobe_of(nc);
    nc->err_ack = info_of(nc, current(nc)->kind)->ack;
}

/* Runs the state machine until it waits for the PLC; 0 or HH_NC_PHASE_TIMEOUT. */
static int step(hh_nc *nc, int64_t cycle, hh_read_bit read_bit, void *ctx, writes *ws)
{
    for (;;) {
        const action *act;
        const kind_info *ki;
        int32_t ack;
        if (nc->head == nc->len)
            return 0;
        act = current(nc);
        ki = info_of(nc, act->kind);
        if (ki->strobe == 0) {
            play_immediate(nc, act, ws);
            complete(nc);
            continue;
        }
        ack = read_bit(ctx, ki->ack) != 0;
        switch (nc->state) {
        case HH_NC_IDLE:
            if (ack)
                return 0; /* the PLC still holds the acknowledgement: the handshake cannot start */
            write_codes(act, ws);
            start_strobe(nc, 0, cycle, ws);
            return 0;
        case HH_NC_WAIT_ACK:
            if (ack) {
                emit(ws, 'M', strobe_of(nc), 0);
                nc->state = HH_NC_WAIT_ACK_RESET;
                return 0; /* the acknowledgement cannot be reset in this same phase */
            }
            break;
        default: /* HH_NC_WAIT_ACK_RESET */
            if (!ack) {
                /* ASSUMPTION (dual-gripper TOOL CALL, spec 12.2/12.3 name M4520 but not its
                 * protocol): the second strobe M4520 is a complete second handshake with the
                 * same acknowledgement M4093, started once the first one has completed, with
                 * W264/W262/M4521-M4523 unchanged. */
                if (act->kind == K_TOOL_CALL && act->c && nc->stage == 0) {
                    start_strobe(nc, 1, cycle, ws);
                    return 0;
                }
                complete(nc);
                continue; /* the next action may start in this same phase (spec 12.3) */
            }
            break;
        }
        if (timed_out(nc, cycle)) {
            fail(nc, cycle);
            return HH_NC_PHASE_TIMEOUT;
        }
        return 0;
    }
}

int hh_nc_phase(hh_nc *nc, int64_t cycle, hh_read_bit read_bit, void *ctx, hh_write *out, int max_out)
{
    hh_write buf[HH_NC_MAX_WRITES];
    hh_nc saved;
    writes ws;
    int rc;
    if (nc->failed)
        return HH_NC_PHASE_TIMEOUT;
    if (cycle != nc->last_cycle + 1)
        return HH_NC_PHASE_SEQUENCE;
    saved = *nc; /* step() never reallocates the queue, so a shallow copy is a full snapshot */
    ws.w = buf;
    ws.n = 0;
    ws.overflow = 0;
    if (nc->profile == HH_NC_PROFILE_ITNC && cycle <= 1) {
        emit(&ws, 'M', nc->first_cycle, cycle == 0);
        if (cycle == 0)
            emit(&ws, 'W', W_MODE, nc->mode);
    }
    if (nc->pulse_program)
        emit(&ws, 'M', M_RESTART_PROGRAM, 0);
    if (nc->pulse_mp)
        emit(&ws, 'M', M_RESTART_MP, 0);
    nc->pulse_program = nc->pulse_mp = 0; /* re-armed by a restart that plays in this phase */
    if (nc->state != HH_NC_IDLE)
        emit(&ws, 'M', strobe_of(nc), nc->state == HH_NC_WAIT_ACK);
    rc = step(nc, cycle, read_bit, ctx, &ws);
    if (rc == 0 && (ws.overflow || ws.n > max_out)) {
        *nc = saved;
        return HH_NC_PHASE_OVERFLOW;
    }
    nc->last_cycle = cycle;
    if (rc < 0)
        return rc;
    if (ws.n > 0)
        memcpy(out, buf, (size_t)ws.n * sizeof *buf);
    return ws.n;
}

int32_t hh_nc_pending(const hh_nc *nc) { return (int32_t)(nc->len - nc->head); }

int32_t hh_nc_state(const hh_nc *nc) { return nc->state; }

const char *hh_nc_active_function(const hh_nc *nc)
{
    return nc->state == HH_NC_IDLE ? NULL : info_of(nc, current(nc)->kind)->name;
}

const char *hh_nc_error(const hh_nc *nc, int64_t *cycle)
{
    if (!nc->failed)
        return NULL;
    if (cycle != NULL)
        *cycle = nc->err_cycle;
    return nc->err_function;
}

int hh_nc_error_detail(const hh_nc *nc, int64_t *started, int32_t *strobe, int32_t *ack)
{
    if (!nc->failed)
        return 0;
    if (started != NULL)
        *started = nc->err_started;
    if (strobe != NULL)
        *strobe = nc->err_strobe;
    if (ack != NULL)
        *ack = nc->err_ack;
    return 1;
}
