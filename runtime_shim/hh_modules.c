/* hh_modules.c - PLC module table, module models and the simulated system context. */
#include "hh_modules.h"

#include <stdlib.h>

typedef struct {
    int32_t number;
    int32_t nparams;
    int32_t nresults;
    int kind; /* HH_MODULE_STUB / HH_MODULE_MODELLED */
    const char *purpose;
} module_entry;

/* Spec 14.2; signatures of the stubs-only entries are unknown, hence 0/0. */
static const module_entry MODULES[] = {
    {9006, 1, 0, HH_MODULE_MODELLED, "start an additional timer T96-T999"},
    {9031, 3, 1, HH_MODULE_MODELLED, "overwrite a machine parameter (run-time value)"},
    {9032, 2, 1, HH_MODULE_MODELLED, "read a machine parameter"},
    {9035, 1, 1, HH_MODULE_MODELLED, "read status information"},
    {9036, 2, 1, HH_MODULE_MODELLED, "write status information"},
    {9040, 2, 0, HH_MODULE_STUB, "read axis coordinates"},
    {9041, 2, 0, HH_MODULE_STUB, "read axis coordinates"},
    {9042, 0, 0, HH_MODULE_STUB, "spindle coordinates"},
    {9051, 0, 0, HH_MODULE_STUB, "binary to ASCII"},
    {9094, 4, 1, HH_MODULE_STUB, "write an element of a tool/datum table"},
    {9095, 0, 0, HH_MODULE_STUB, "nonlinear compensation"},
    {9097, 2, 1, HH_MODULE_STUB, "select a geometry description"},
    {9105, 0, 0, HH_MODULE_STUB, "binary data over the serial interface"},
    {9106, 0, 0, HH_MODULE_STUB, "binary data over the serial interface"},
    {9123, 0, 0, HH_MODULE_STUB, "PLC axes"},
    {9124, 0, 0, HH_MODULE_STUB, "PLC axes"},
    {9148, 0, 0, HH_MODULE_STUB, "named in the sources without a signature"},
    {9150, 0, 0, HH_MODULE_STUB, "named in the sources without a signature"},
    {9159, 0, 0, HH_MODULE_STUB, "named in the sources without a signature"},
    {9162, 0, 0, HH_MODULE_STUB, "named in the sources without a signature"},
    {9166, 0, 0, HH_MODULE_STUB, "named in the sources without a signature"},
    {9190, 0, 0, HH_MODULE_STUB, "operating hours"},
    {9191, 0, 0, HH_MODULE_STUB, "operating hours"},
    {9192, 1, 1, HH_MODULE_MODELLED, "read an operating time in seconds"},
    {9194, 0, 0, HH_MODULE_STUB, "maintenance alarm"},
    {9195, 0, 1, HH_MODULE_MODELLED, "system time"},
    {9429, 0, 0, HH_MODULE_STUB, "MANUALplus API module"},
};

#define N_MODULES ((int32_t)(sizeof MODULES / sizeof MODULES[0]))
#define MP_TIMER_EXTRA 4111
#define MAX_MANTISSA 1000000000000000LL /* 10^15: keeps mantissa * 1000 and 10^9 * ms in int64 */

typedef struct {
    int32_t number, index;
    int64_t mantissa; /* run-time value: from the MP file/scenario, overwritten by module 9031 */
    int32_t decimals;
} mp_entry;

typedef struct {
    int32_t number, index, value;
} override_entry;

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
    return m ? m->kind : HH_MODULE_UNKNOWN;
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
    free(sys);
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

void hh_sys_tick(hh_sys *sys) { sys->cycle++; }

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

static int call_9036(hh_sys *sys, const int32_t *p, int32_t *r, int32_t *code)
{
    if (p[0] < 0 || p[0] >= HH_STATUS_SIZE) {
        r[0] = 1;
        *code = HH_MODERR_PARAM;
        return 1;
    }
    sys->status[p[0]] = p[1];
    r[0] = 0;
    return 0;
}

static int call_9192(hh_sys *sys, const int32_t *p, int32_t *r)
{
    r[0] = p[0] >= -3 && p[0] <= -1 ? clock_seconds(sys) : -1;
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
    case 9192: return call_9192(sys, p, r);
    case 9195: r[0] = clock_seconds(sys); return 0;
    default: /* stub rule of A-46 */
        for (i = 0; i < m->nresults; i++)
            r[i] = 0;
        return 0;
    }
}

int hh_module_call(hh_sys *sys, int32_t number, const int32_t *params, int32_t *results, int32_t *error_code)
{
    const module_entry *m = find_module(number);
    int32_t code = 0;
    int status;
    size_t i;
    if (m == NULL) {
        *error_code = 0;
        return -1;
    }
    status = run_model(sys, m, params, results, &code);
    for (i = 0; i < sys->n_overrides; i++)
        if (sys->overrides[i].number == number)
            results[sys->overrides[i].index] = sys->overrides[i].value;
    *error_code = status ? code : 0;
    return status;
}
