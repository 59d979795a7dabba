/* hh_modules.c - PLC module table, module models and the simulated system context. */
#include "hh_modules.h"

#include <stdlib.h>
#include <string.h>

typedef struct {
    int32_t number;
    int32_t nparams;
    int32_t nresults;
    int kind;     /* HH_KIND_PURE / HH_KIND_DATA / HH_KIND_MACHINE */
    int context;  /* HH_CTX_ANY / HH_CTX_CYCLIC / HH_CTX_SUBMIT */
    int strobe;   /* bound to a pending strobe while an NC program runs (not checked: no program runs) */
    int modelled; /* 0: the stub rule of A-46 (results 0, no error) */
    int profiles; /* bit mask, see hh_module_table.h */
    int error_result; /* index of a result that also carries the error code, -1 none */
    int context_code; /* W1022 code of a call in the wrong context, 0: HH_MODERR_NOT_IN_JOB / _NOT_CYCLIC */
    int context_result_set; /* 1: the error result takes context_result then, 0: it takes the code */
    int context_result;
    const char *purpose;
} module_entry;

/* The rows are generated from the Python module table (one source for both executors). */
#include "hh_module_table.h"

#define N_MODULES ((int32_t)(sizeof MODULES / sizeof MODULES[0]))
#define MP_TIMER_EXTRA 4111
#define MP_HANDWHEEL_INTERPOLATION 7641 /* 9036: interpolation factors need MP7641 = 1 */
#define SUBMIT_QUEUE_ID ((int32_t)0x80000000u) /* 9261: K$80000000 addresses the submit queue */
#define MAX_MANTISSA 1000000000000000LL /* 10^15: keeps mantissa * 1000 and 10^9 * ms in int64 */

typedef struct {
    int32_t number, index;
    int64_t mantissa; /* run-time value: from the MP file/scenario, overwritten by module 9031 */
    int32_t decimals;
} mp_entry;

typedef struct {
    int32_t number, index, value;
} override_entry;

typedef struct {
    int32_t type, line, element, value;
} table_entry;

struct hh_sys {
    int32_t cycle_time_ms;
    int64_t cycle;
    mp_entry *mps;
    size_t n_mps, cap_mps;
    override_entry *overrides;
    size_t n_overrides, cap_overrides;
    int32_t number_mp4111;
    int32_t timer_unit_cycles;
    int32_t timer_restart;
    int32_t status[HH_STATUS_SIZE];
    table_entry *tables;
    size_t n_tables, cap_tables;
    int32_t axes_active;                  /* bit n = axis n+1 exists and is active (9038 info 0) */
    int32_t axis_pos[HH_AXES];            /* actual REF positions, 0.0001 mm (9049 info 2) */
    int32_t drives_available;             /* drives whose power stage is ready (9162 = available & enabled) */
    int32_t drives_enabled;               /* written by 9161 */
    int32_t drives_i32;                   /* written by 9169 */
    int32_t drives_switching_off;         /* 9159 early warning, from the scenario */
    int32_t counters_running;             /* bits 0..7: PLC operating-hours counters 1..8 (9190/9191) */
    int64_t counter_ms[HH_HOUR_COUNTERS];
    int32_t mem_size;                     /* bytes of the B/W/D memory, 0 unknown (9040/9042 block check) */
    int64_t safety_test_until;            /* 9144: a self test is active while cycle < this */
    int32_t rem[HH_EXTRA_TIMER_COUNT];
    unsigned char start[HH_EXTRA_TIMER_COUNT];
};

static const module_entry *find_module(int32_t number)
{
    int32_t i;
    for (i = 0; i < N_MODULES; i++)
        if (MODULES[i].number == number)
            return &MODULES[i];
    return NULL;
}

int hh_module_info(int32_t number, int32_t *nparams, int32_t *nresults)
{
    const module_entry *m = find_module(number);
    if (nparams != NULL)
        *nparams = m ? m->nparams : 0;
    if (nresults != NULL)
        *nresults = m ? m->nresults : 0;
    return m ? (m->modelled ? HH_MODULE_MODELLED : HH_MODULE_STUB) : HH_MODULE_UNKNOWN;
}

int hh_module_meta(int32_t number, int32_t *kind, int32_t *context, int32_t *strobe, int32_t *profiles,
                   int32_t *error_result)
{
    const module_entry *m = find_module(number);
    if (m == NULL)
        return 0;
    *kind = m->kind;
    *context = m->context;
    *strobe = m->strobe;
    *profiles = m->profiles;
    *error_result = m->error_result;
    return 1;
}

const char *hh_module_purpose(int32_t number)
{
    const module_entry *m = find_module(number);
    return m ? m->purpose : "";
}

int32_t hh_module_count(void) { return N_MODULES; }

int32_t hh_module_number_at(int32_t i) { return i >= 0 && i < N_MODULES ? MODULES[i].number : 0; }

hh_sys *hh_sys_new(int32_t cycle_time_ms)
{
    hh_sys *sys;
    if (cycle_time_ms <= 0)
        return NULL;
    sys = (hh_sys *)calloc(1, sizeof *sys);
    if (sys == NULL)
        return NULL;
    sys->cycle_time_ms = cycle_time_ms;
    sys->timer_restart = 1;
    return sys;
}

void hh_sys_free(hh_sys *sys)
{
    if (sys == NULL)
        return;
    free(sys->mps);
    free(sys->overrides);
    free(sys->tables);
    free(sys);
}

/* A deep copy of `sys` (NULL when memory is exhausted): the co-simulation gives the translated program a
 * system context of its own that starts exactly where the reference interpreter's does. */
static void *copy_items(const void *items, size_t n, size_t size)
{
    void *out;
    if (n == 0 || items == NULL)
        return NULL;
    out = malloc(n * size);
    if (out != NULL)
        memcpy(out, items, n * size);
    return out;
}

hh_sys *hh_sys_clone(const hh_sys *sys)
{
    hh_sys *copy;
    if (sys == NULL)
        return NULL;
    copy = (hh_sys *)malloc(sizeof *copy);
    if (copy == NULL)
        return NULL;
    *copy = *sys;
    copy->mps = (mp_entry *)copy_items(sys->mps, sys->n_mps, sizeof *sys->mps);
    copy->overrides = (override_entry *)copy_items(sys->overrides, sys->n_overrides, sizeof *sys->overrides);
    copy->tables = (table_entry *)copy_items(sys->tables, sys->n_tables, sizeof *sys->tables);
    copy->cap_mps = sys->n_mps;
    copy->cap_overrides = sys->n_overrides;
    copy->cap_tables = sys->n_tables;
    if ((sys->n_mps && copy->mps == NULL) || (sys->n_overrides && copy->overrides == NULL)
            || (sys->n_tables && copy->tables == NULL)) {
        hh_sys_free(copy);
        return NULL;
    }
    return copy;
}

/* `items` with room for element n (doubling, `first` elements at first), or NULL when memory is
 * exhausted (`items` is then unchanged). */
static void *reserve(void *items, size_t n, size_t *cap, size_t first, size_t size)
{
    size_t grown;
    if (n < *cap)
        return items;
    grown = *cap ? *cap * 2 : first;
    items = realloc(items, grown * size);
    if (items != NULL)
        *cap = grown;
    return items;
}

static mp_entry *find_mp(const hh_sys *sys, int32_t number, int32_t index)
{
    size_t i;
    for (i = 0; i < sys->n_mps; i++)
        if (sys->mps[i].number == number && sys->mps[i].index == index)
            return &sys->mps[i];
    return NULL;
}

int hh_sys_set_mp(hh_sys *sys, int32_t number, int32_t index, int64_t mantissa, int32_t decimals)
{
    mp_entry *e;
    if (decimals < 0 || decimals > 9 || mantissa >= MAX_MANTISSA || mantissa <= -MAX_MANTISSA)
        return -1;
    e = find_mp(sys, number, index);
    if (e == NULL) {
        mp_entry *p = (mp_entry *)reserve(sys->mps, sys->n_mps, &sys->cap_mps, 32, sizeof *p);
        if (p == NULL)
            return -1;
        sys->mps = p;
        e = &sys->mps[sys->n_mps++];
        e->number = number;
        e->index = index;
    }
    e->mantissa = mantissa;
    e->decimals = decimals;
    return 0;
}

int hh_sys_get_mp(const hh_sys *sys, int32_t number, int32_t index, int64_t *mantissa, int32_t *decimals)
{
    const mp_entry *e = find_mp(sys, number, index);
    if (e == NULL)
        return 0;
    if (mantissa != NULL)
        *mantissa = e->mantissa;
    if (decimals != NULL)
        *decimals = e->decimals;
    return 1;
}

int hh_sys_set_number_mp4111(hh_sys *sys, int32_t count)
{
    if (count < 0 || count > HH_EXTRA_TIMER_COUNT)
        return -1;
    sys->number_mp4111 = count;
    return 0;
}

void hh_sys_set_timer_unit(hh_sys *sys, int32_t cycles) { sys->timer_unit_cycles = cycles != 0; }

void hh_sys_set_timer_restart(hh_sys *sys, int32_t restart) { sys->timer_restart = restart != 0; }

int hh_sys_set_status(hh_sys *sys, int32_t number, int32_t value)
{
    if (number < 0 || number >= HH_STATUS_SIZE)
        return -1;
    sys->status[number] = value;
    return 0;
}

int hh_sys_set_module_result(hh_sys *sys, int32_t number, int32_t index, int32_t value)
{
    const module_entry *m = find_module(number);
    override_entry *p;
    size_t i;
    if (m == NULL || index < 0 || index >= m->nresults)
        return -1;
    for (i = 0; i < sys->n_overrides; i++) {
        if (sys->overrides[i].number == number && sys->overrides[i].index == index) {
            sys->overrides[i].value = value;
            return 0;
        }
    }
    p = (override_entry *)reserve(sys->overrides, sys->n_overrides, &sys->cap_overrides, 8, sizeof *p);
    if (p == NULL)
        return -1;
    sys->overrides = p;
    sys->overrides[sys->n_overrides].number = number;
    sys->overrides[sys->n_overrides].index = index;
    sys->overrides[sys->n_overrides].value = value;
    sys->n_overrides++;
    return 0;
}

void hh_sys_clear_module_results(hh_sys *sys, int32_t number)
{
    size_t i, kept = 0;
    for (i = 0; i < sys->n_overrides; i++)
        if (sys->overrides[i].number != number)
            sys->overrides[kept++] = sys->overrides[i];
    sys->n_overrides = kept;
}

void hh_sys_tick(hh_sys *sys)
{
    int32_t i;
    sys->cycle++;
    for (i = 0; i < HH_HOUR_COUNTERS; i++)
        if (sys->counters_running & (1 << i))
            sys->counter_ms[i] += sys->cycle_time_ms;
}

int hh_sys_set_axis(hh_sys *sys, int32_t axis, int32_t active, int32_t position)
{
    if (axis < 0 || axis >= HH_AXES)
        return -1;
    sys->axes_active = active ? sys->axes_active | (1 << axis) : sys->axes_active & ~(1 << axis);
    sys->axis_pos[axis] = position;
    return 0;
}

void hh_sys_set_memory_size(hh_sys *sys, int32_t bytes) { sys->mem_size = bytes > 0 ? bytes : 0; }

void hh_sys_set_drives(hh_sys *sys, int32_t available, int32_t switching_off)
{
    sys->drives_available = available;
    sys->drives_switching_off = switching_off;
}

static table_entry *find_table(const hh_sys *sys, int32_t type, int32_t line, int32_t element)
{
    size_t i;
    for (i = 0; i < sys->n_tables; i++)
        if (sys->tables[i].type == type && sys->tables[i].line == line && sys->tables[i].element == element)
            return &sys->tables[i];
    return NULL;
}

int hh_sys_set_table(hh_sys *sys, int32_t type, int32_t line, int32_t element, int32_t value)
{
    table_entry *e;
    if (type < 0 || type > 2 || line < 0 || element < 0 || element > HH_TABLE_ELEMENTS)
        return -1;
    e = find_table(sys, type, line, element);
    if (e == NULL) {
        table_entry *p = (table_entry *)reserve(sys->tables, sys->n_tables, &sys->cap_tables, 16, sizeof *p);
        if (p == NULL)
            return -1;
        sys->tables = p;
        e = &sys->tables[sys->n_tables++];
        e->type = type;
        e->line = line;
        e->element = element;
    }
    e->value = value;
    return 0;
}

static int table_has_line(const hh_sys *sys, int32_t type, int32_t line)
{
    size_t i;
    for (i = 0; i < sys->n_tables; i++)
        if (sys->tables[i].type == type && sys->tables[i].line == line)
            return 1;
    return 0;
}

static int table_has_type(const hh_sys *sys, int32_t type)
{
    size_t i;
    for (i = 0; i < sys->n_tables; i++)
        if (sys->tables[i].type == type)
            return 1;
    return 0;
}

int64_t hh_sys_cycle(const hh_sys *sys) { return sys->cycle; }

int64_t hh_sys_time_ms(const hh_sys *sys) { return sys->cycle * (int64_t)sys->cycle_time_ms; }

static int32_t saturate(int64_t v)
{
    return v > INT32_MAX ? INT32_MAX : v < INT32_MIN ? INT32_MIN : (int32_t)v;
}

static int64_t pow10_of(int32_t decimals)
{
    int64_t p = 1;
    while (decimals-- > 0)
        p *= 10;
    return p;
}

/* Preset in cycles of additional timer n from the run-time MP4111.n (spec 9.3). */
static int32_t extra_timer_preset(const hh_sys *sys, int32_t n)
{
    const mp_entry *e = find_mp(sys, MP_TIMER_EXTRA, n);
    int64_t num, den;
    if (e == NULL || e->mantissa <= 0)
        return 0;
    /* seconds: ceil(m / 10^d s / (ms / 1000)) = ceil(m * 1000 / (10^d * ms)); cycles: ceil(m / 10^d) */
    num = sys->timer_unit_cycles ? e->mantissa : e->mantissa * 1000;
    den = sys->timer_unit_cycles ? pow10_of(e->decimals) : pow10_of(e->decimals) * sys->cycle_time_ms;
    return saturate((num + den - 1) / den);
}

int hh_sys_service(hh_sys *sys, hh_write *out, int max_out)
{
    int32_t i, n = sys->number_mp4111;
    for (i = 0; i < n; i++) {
        int running = sys->rem[i] > 0;
        if (sys->start[i] && (!running || sys->timer_restart))
            sys->rem[i] = extra_timer_preset(sys, HH_EXTRA_TIMER_FIRST + i);
        else if (sys->rem[i] > 0)
            sys->rem[i]--;
        sys->start[i] = 0;
    }
    if (out == NULL)
        return 0;
    if (max_out < n)
        return -1;
    for (i = 0; i < n; i++) {
        out[i].kind = 'T';
        out[i].addr = HH_EXTRA_TIMER_FIRST + i;
        out[i].value = sys->rem[i] > 0;
    }
    return n;
}

int hh_sys_timer_running(const hh_sys *sys, int32_t n)
{
    if (n < HH_EXTRA_TIMER_FIRST || n > HH_EXTRA_TIMER_LAST)
        return 0;
    return sys->rem[n - HH_EXTRA_TIMER_FIRST] > 0;
}

static int32_t clock_seconds(const hh_sys *sys) { return saturate(hh_sys_time_ms(sys) / 1000); }

/* Each model returns the error status and sets *code (W1022) on error. */
static int call_9006(hh_sys *sys, const int32_t *p, int32_t *code)
{
    int32_t n = p[0];
    if (n < HH_EXTRA_TIMER_FIRST || n >= HH_EXTRA_TIMER_FIRST + sys->number_mp4111) {
        *code = HH_MODERR_PARAM;
        return 1;
    }
    sys->start[n - HH_EXTRA_TIMER_FIRST] = 1;
    return 0;
}

static int call_9031(hh_sys *sys, const int32_t *p, int32_t *r, int32_t *code)
{
    mp_entry *e = find_mp(sys, p[0], p[1]);
    if (e == NULL) {
        r[0] = 1;
        *code = 1;
        return 1;
    }
    e->mantissa = p[2];
    r[0] = 0;
    return 0;
}

static int call_9032(hh_sys *sys, const int32_t *p, int32_t *r, int32_t *code)
{
    const mp_entry *e = find_mp(sys, p[0], p[1]);
    if (e == NULL) {
        r[0] = 0;
        *code = HH_MODERR_PARAM;
        return 1;
    }
    r[0] = saturate(e->mantissa);
    return 0;
}

static int call_9035(hh_sys *sys, const int32_t *p, int32_t *r, int32_t *code)
{
    if (p[0] < 0 || p[0] >= HH_STATUS_SIZE) {
        r[0] = 0;
        *code = HH_MODERR_PARAM;
        return 1;
    }
    r[0] = sys->status[p[0]];
    return 0;
}

static int call_9192(hh_sys *sys, const int32_t *p, int32_t *r, int32_t *code)
{
    if (p[0] >= -3 && p[0] <= -1) {
        r[0] = clock_seconds(sys);
        return 0;
    }
    if (p[0] >= 0 && p[0] < HH_HOUR_COUNTERS) {
        r[0] = saturate(sys->counter_ms[p[0]] / 1000);
        return 0;
    }
    r[0] = -1;
    *code = HH_MODERR_PARAM;
    return 1;
}

/* 9092/9093/9094: file type 0 .T, 1 .D, 2 .TCH; the table store holds what the scenario loaded. */
static int table_error(const hh_sys *sys, int32_t type, int32_t line, int32_t element)
{
    if (type < 0 || type > 2)
        return 2;
    if (!table_has_type(sys, type))
        return 3;
    if (line < 0 || !table_has_line(sys, type, line))
        return 4;
    if (element < 0 || element > HH_TABLE_ELEMENTS)
        return 5;
    return 0;
}

static int call_9092(hh_sys *sys, const int32_t *p, int32_t *r, int32_t *code)
{
    size_t i;
    int32_t best = -1;
    int err = p[0] < 0 || p[0] > 2 ? 2 : !table_has_type(sys, p[0]) ? 3 : p[1] < 0 || p[1] > HH_TABLE_ELEMENTS ? 5 : 0;
    if (err == 0) {
        for (i = 0; i < sys->n_tables; i++) {
            const table_entry *e = &sys->tables[i];
            if (e->type == p[0] && e->element == p[1] && e->value == p[2] && (best < 0 || e->line < best))
                best = e->line;
        }
        if (best < 0)
            err = 6;
    }
    r[0] = best;
    r[1] = err;
    *code = err;
    return err != 0;
}

static int call_9093(hh_sys *sys, const int32_t *p, int32_t *r, int32_t *code)
{
    const table_entry *e;
    int err = table_error(sys, p[0], p[1], p[2]);
    e = err ? NULL : find_table(sys, p[0], p[1], p[2]);
    r[0] = e ? e->value : 0; /* an element the table does not fill reads 0 */
    r[1] = err;
    *code = err;
    return err != 0;
}

static int call_9094(hh_sys *sys, const int32_t *p, int32_t *r, int32_t *code)
{
    int err = table_error(sys, p[0], p[1], p[2]);
    if (err == 0 && hh_sys_set_table(sys, p[0], p[1], p[2], p[3]) != 0)
        err = 6;
    r[0] = err;
    *code = err;
    return err != 0;
}

static int call_9038(hh_sys *sys, const int32_t *p, int32_t *r, int32_t *code)
{
    int32_t axis = p[0], info = p[1];
    r[0] = 0;
    if (info < 0 || info > 9) {
        *code = 1;
        return 1;
    }
    if (axis != -1 && (axis < 0 || axis >= HH_AXES)) {
        *code = 2;
        return 1;
    }
    /* Only info 0 (axis active) has data; the other infos read 0 (assumption A-46c). */
    if (info == 0)
        r[0] = axis == -1 ? sys->axes_active : (sys->axes_active >> axis) & 1;
    return 0;
}

static int call_9049(hh_sys *sys, const int32_t *p, int32_t *r, int32_t *code)
{
    int32_t axis = p[0], info = p[1];
    r[0] = 0;
    if (axis < 0 || axis >= HH_AXES || !(info == 2 || info == 3 || (info >= 8 && info <= 11))) {
        *code = 2;
        return 1;
    }
    if (info == 2)
        r[0] = sys->axis_pos[axis];
    return 0;
}

static int call_counters(hh_sys *sys, int32_t mask, int start, int32_t *code)
{
    if (mask & ~((1 << HH_HOUR_COUNTERS) - 1)) {
        *code = HH_MODERR_PARAM;
        return 1;
    }
    sys->counters_running = start ? sys->counters_running | mask : sys->counters_running & ~mask;
    return 0;
}

/* Sets the error result (when the module has one) and the W1022 code; returns the error status 1. */
static int fail(int32_t *r, int32_t result, int32_t *code, int32_t w1022)
{
    r[0] = result;
    *code = w1022;
    return 1;
}

static int axis_ok(int32_t axis) { return axis >= 0 && axis < HH_AXES; }

/* 9036 numbers (T407/T426): 0-4 and 11-19 interpolation factor of one axis, 5 all axes (0..10 each),
 * 6 handwheel axis, 7-9 reserved, 10 jog-increment limit. */
static int interpolation_number(int32_t n) { return (n >= 0 && n <= 5) || (n >= 11 && n <= 19); }

static int call_9036(hh_sys *sys, const int32_t *p, int32_t *r, int32_t *code)
{
    int32_t n = p[0], v = p[1];
    const mp_entry *mp7641;
    if (n < 0 || n > 19)
        return fail(r, 1, code, 2); /* wrong number: error result 1, W1022 2 (TNC 426) */
    if (interpolation_number(n)) {
        if (v < 0 || v > 10)
            return fail(r, 2, code, 1); /* value out of range: error result 2, W1022 1 */
        mp7641 = find_mp(sys, MP_HANDWHEEL_INTERPOLATION, 0);
        if (mp7641 != NULL && mp7641->mantissa != pow10_of(mp7641->decimals))
            return fail(r, 3, code, 6); /* input disabled: error result 3, W1022 6 */
    }
    sys->status[n] = v;
    r[0] = 0;
    return 0;
}

/* A D address whose `dwords` double words fit the memory (when its size is known). */
static int dword_block_ok(const hh_sys *sys, int32_t addr, int32_t dwords)
{
    if (addr < 0 || addr % 4 != 0)
        return 0;
    return sys->mem_size == 0 || (int64_t)addr + 4 * (int64_t)dwords <= sys->mem_size;
}

static int call_9040(hh_sys *sys, const int32_t *p, int32_t *code)
{
    if (p[1] < 0 || p[1] > 4 || !dword_block_ok(sys, p[0], 5)) {
        *code = HH_MODERR_PARAM;
        return 1;
    }
    return 0; /* coordinates depend on the machine: the memory is not written (A-46t) */
}

static int call_9042(hh_sys *sys, const int32_t *p, int32_t *code)
{
    if (!dword_block_ok(sys, p[0], 5)) {
        *code = HH_MODERR_PARAM;
        return 1;
    }
    return 0;
}

static int call_9048(const int32_t *p, int32_t *r, int32_t *code)
{
    r[0] = 0; /* no brake test, no free rotation in simulation (A-46u) */
    if (p[1] != 0 && p[1] != 1)
        return fail(r, 0, code, 1);
    if (p[0] != -1 && !axis_ok(p[0]))
        return fail(r, 0, code, 2);
    return 0;
}

static int call_9095(const int32_t *p, int32_t *r, int32_t *code)
{
    if (p[0] < 0)
        return fail(r, 1, code, 1); /* line missing */
    r[0] = 0;
    return 0;
}

static int call_9097(const int32_t *p, int32_t *r, int32_t *code)
{
    if (p[1] != 0)
        return fail(r, 1, code, 2); /* bad mode: W1022 2 groups the configuration errors */
    if (p[0] < 0)
        return fail(r, 2, code, 2); /* line missing */
    r[0] = 0;
    return 0;
}

static int call_9102(const int32_t *p, int32_t *r, int32_t *code)
{
    if (p[0] != 0 && p[0] != 1)
        return fail(r, -1, code, 1);
    r[0] = 0; /* not assigned: 9100 has no model (A-46x) */
    return 0;
}

static int call_9105(const int32_t *p, int32_t *code)
{
    int32_t interface = p[0], addr = p[1], len = p[2];
    if (interface < 0 || interface > 1 || addr < 0 || addr > 1023 || len < 0 || len > 63 || addr + len > 1024) {
        *code = HH_MODERR_PARAM;
        return 1;
    }
    return 0;
}

static int call_9124(const int32_t *p, int32_t *r, int32_t *code)
{
    if (!axis_ok(p[0]))
        return fail(r, 1, code, 1);
    if (p[1] < 0 || p[1] > 10000)
        return fail(r, 3, code, 3);
    r[0] = 0;
    return 0;
}

static int call_9127(const int32_t *p, int32_t *r, int32_t *code)
{
    if (!axis_ok(p[0]))
        return fail(r, 0, code, 1);
    if (p[1] < 0 || p[1] > 3)
        return fail(r, 0, code, 2);
    r[0] = 0; /* no axis is coupled in simulation */
    return 0;
}

static int call_9144(hh_sys *sys, const int32_t *p, int32_t *r, int32_t *code)
{
    int32_t mode = p[0], p1 = p[1];
    r[0] = 0;
    if (mode == 10 ? p1 < 0 || p1 > 2 : mode == 11 ? !axis_ok(p1) : mode != 0)
        return fail(r, 0, code, 2);
    if (mode == 0) {
        if (sys->cycle < sys->safety_test_until)
            return fail(r, 0, code, 28); /* test already active */
        sys->safety_test_until = sys->cycle + 1; /* runs to the end of this cycle (A-46z) */
    }
    return 0;
}

static int call_9150(const int32_t *p, int32_t *r, int32_t *code)
{
    if (p[0] != 0)
        return fail(r, 2, code, 2); /* unknown code: only TOOL CALL (0) */
    r[0] = 0;
    return 0;
}

static int call_9194(const int32_t *p, int32_t *code)
{
    if (p[0] < -3 || p[0] >= HH_HOUR_COUNTERS || p[2] < 0) {
        *code = HH_MODERR_PARAM;
        return 1;
    }
    return 0; /* the alarm marker is not set in simulation (A-46l2) */
}

static int call_9231(const int32_t *p, int32_t *code)
{
    if (p[0] < 0 || p[0] > 8) {
        *code = 1;
        return 1;
    }
    if (p[1] < -30000 || p[1] > 30000) {
        *code = 2;
        return 1;
    }
    return 0;
}

static int call_9244(const int32_t *p, int32_t *r, int32_t *code)
{
    if (p[1] < 0 || p[1] > 7)
        return fail(r, -1, code, 3);
    if (p[0] < 0)
        return fail(r, -1, code, 2);
    r[0] = 0; /* files depend on the machine: nothing written (A-46x) */
    return 0;
}

static int call_9260(const int32_t *p, int32_t *r, int32_t *code)
{
    r[0] = 0; /* no events are delivered in simulation (A-46e2) */
    if (p[0] != 0 && p[0] != -1)
        return fail(r, 0, code, 2);
    return 0;
}

static int call_9261(const int32_t *p, int32_t *code)
{
    if (p[0] != SUBMIT_QUEUE_ID) {
        *code = 30; /* SPAWN has no model: no process has another identifier */
        return 1;
    }
    return 0;
}

static int call_9429(const int32_t *p, int32_t *r, int32_t *code)
{
    int32_t i;
    for (i = 0; i < 4; i++)
        r[i] = 0;
    if (p[0] != 0 || p[2] < 0 || p[2] > 3 || p[1] < 0) {
        *code = 1;
        return 1;
    }
    r[0] = 2; /* no NC program runs in simulation: finished (A-46p2) */
    return 0;
}

static int run_model(hh_sys *sys, const module_entry *m, const int32_t *p, int32_t *r, int32_t *code)
{
    int32_t i;
    switch (m->number) {
    case 9006: return call_9006(sys, p, code);
    case 9031: return call_9031(sys, p, r, code);
    case 9032: return call_9032(sys, p, r, code);
    case 9035: return call_9035(sys, p, r, code);
    case 9036: return call_9036(sys, p, r, code);
    case 9192: return call_9192(sys, p, r, code);
    case 9092: return call_9092(sys, p, r, code);
    case 9093: return call_9093(sys, p, r, code);
    case 9094: return call_9094(sys, p, r, code);
    case 9038: return call_9038(sys, p, r, code);
    case 9049: return call_9049(sys, p, r, code);
    case 9159: r[0] = sys->drives_switching_off; return 0;
    case 9161: sys->drives_enabled = p[0]; return 0;
    case 9162: r[0] = sys->drives_available & sys->drives_enabled; return 0;
    case 9169: sys->drives_i32 = p[0]; return 0;
    case 9190: return call_counters(sys, p[0], 1, code);
    case 9191: return call_counters(sys, p[0], 0, code);
    case 9195: r[0] = clock_seconds(sys); return 0;
    case 9040: return call_9040(sys, p, code);
    case 9042: return call_9042(sys, p, code);
    case 9048: return call_9048(p, r, code);
    case 9095: return call_9095(p, r, code);
    case 9097: return call_9097(p, r, code);
    case 9102: return call_9102(p, r, code);
    case 9105: return call_9105(p, code);
    case 9124: return call_9124(p, r, code);
    case 9127: return call_9127(p, r, code);
    case 9144: return call_9144(sys, p, r, code);
    case 9150: return call_9150(p, r, code);
    case 9194: return call_9194(p, code);
    case 9231: return call_9231(p, code);
    case 9244: return call_9244(p, r, code);
    case 9260: return call_9260(p, r, code);
    case 9261: return call_9261(p, code);
    case 9429: return call_9429(p, r, code);
    default: /* stub rule of A-46 */
        for (i = 0; i < m->nresults; i++)
            r[i] = 0;
        return 0;
    }
}

int hh_module_call(hh_sys *sys, int32_t number, const int32_t *params, int32_t *results, int32_t *error_code)
{
    return hh_module_call_ctx(sys, number, HH_CALLER_ANY, params, results, error_code);
}

int hh_module_call_ctx(hh_sys *sys, int32_t number, int32_t caller, const int32_t *params, int32_t *results,
                       int32_t *error_code)
{
    const module_entry *m = find_module(number);
    int32_t code = 0, i;
    int status;
    size_t k;
    if (m == NULL) {
        *error_code = 0;
        return -1;
    }
    if (caller == HH_CALLER_CYCLIC && m->context == HH_CTX_SUBMIT)
        code = m->context_code ? m->context_code : HH_MODERR_NOT_IN_JOB;
    else if (caller == HH_CALLER_JOB && m->context == HH_CTX_CYCLIC)
        code = m->context_code ? m->context_code : HH_MODERR_NOT_CYCLIC;
    if (code != 0) { /* the module does nothing; an error result carries the code, or the module's own
                      * documented number for the wrong context (A-46q) */
        for (i = 0; i < m->nresults; i++)
            results[i] = 0;
        if (m->error_result >= 0)
            results[m->error_result] = m->context_result_set ? m->context_result : code;
        *error_code = code;
        return 1;
    }
    status = run_model(sys, m, params, results, &code);
    for (k = 0; k < sys->n_overrides; k++)
        if (sys->overrides[k].number == number)
            results[sys->overrides[k].index] = sys->overrides[k].value;
    *error_code = status ? code : 0;
    return status;
}
