/* test_modules.c - unit tests of the module table, the module models and the 9006 timers. */
#include <string.h>

#include "hh_modules.h"
#include "hh_test.h"

static int32_t results[HH_MODULE_MAX_RESULTS];
static int32_t code;

static int call(hh_sys *sys, int32_t number, int32_t p0, int32_t p1, int32_t p2)
{
    int32_t params[3];
    params[0] = p0;
    params[1] = p1;
    params[2] = p2;
    memset(results, 0x5a, sizeof results); /* garbage a model must overwrite */
    code = -99;
    return hh_module_call(sys, number, params, results, &code);
}

static void module_table(void)
{
    static const int32_t rows[][4] = {
        /* number, kind, nparams, nresults */
        {9006, HH_MODULE_MODELLED, 1, 0}, {9031, HH_MODULE_MODELLED, 3, 1},
        {9032, HH_MODULE_MODELLED, 2, 1}, {9035, HH_MODULE_MODELLED, 1, 1},
        {9036, HH_MODULE_MODELLED, 2, 1}, {9192, HH_MODULE_MODELLED, 1, 1},
        {9195, HH_MODULE_MODELLED, 0, 1}, {9040, HH_MODULE_MODELLED, 2, 0},
        {9094, HH_MODULE_MODELLED, 4, 1}, {9097, HH_MODULE_MODELLED, 2, 1},
        {9042, HH_MODULE_MODELLED, 1, 0}, {9194, HH_MODULE_MODELLED, 3, 0},
        {9080, HH_MODULE_STUB, 0, 0},     {9263, HH_MODULE_STUB, 1, 0},
        {9999, HH_MODULE_UNKNOWN, 0, 0},  {0, HH_MODULE_UNKNOWN, 0, 0},
    };
    size_t i;
    int32_t k, seen_9429 = 0;
    for (i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        int32_t np = -1, nr = -1;
        CHECK_EQ(hh_module_info(rows[i][0], &np, &nr), rows[i][1]);
        CHECK_EQ(np, rows[i][2]);
        CHECK_EQ(nr, rows[i][3]);
    }
    CHECK(strlen(hh_module_purpose(9192)) > 0);
    CHECK_EQ(strlen(hh_module_purpose(9999)), 0);
    for (k = 0; k < hh_module_count(); k++) {
        CHECK(hh_module_info(hh_module_number_at(k), NULL, NULL) != HH_MODULE_UNKNOWN);
        seen_9429 |= hh_module_number_at(k) == 9429;
    }
    CHECK(seen_9429);
}

static void unknown_and_stub_calls(void)
{
    hh_sys *sys = hh_sys_new(20);
    CHECK_EQ(call(sys, 9999, 0, 0, 0), -1);
    CHECK_EQ(code, 0);
    CHECK_EQ(call(sys, 9081, 0, 0, 0), 0); /* stub rule A-46: results 0, no error */
    CHECK_EQ(results[0], 0);
    CHECK_EQ(code, 0);
    hh_sys_free(sys);
}

/* Runs phase 3 for the additional timers, returning the running bit of T96 as written. */
static int32_t service_t96(hh_sys *sys)
{
    hh_write out[HH_EXTRA_TIMER_COUNT];
    int n = hh_sys_service(sys, out, HH_EXTRA_TIMER_COUNT);
    CHECK(n >= 1);
    CHECK(out[0].kind == 'T' && out[0].addr == 96);
    CHECK_EQ(out[0].value, hh_sys_timer_running(sys, 96));
    return out[0].value;
}

static void timer_9006_needs_numbermp4111(void)
{
    hh_sys *sys = hh_sys_new(20);
    CHECK_EQ(call(sys, 9006, 96, 0, 0), 1); /* NUMBERMP4111 defaults to 0 (17b.10) */
    CHECK_EQ(code, HH_MODERR_PARAM);
    CHECK_EQ(hh_sys_service(sys, NULL, 0), 0);
    CHECK_EQ(hh_sys_timer_running(sys, 96), 0);
    CHECK_EQ(hh_sys_set_number_mp4111(sys, 4), 0);
    CHECK_EQ(hh_sys_set_number_mp4111(sys, 905), -1);
    CHECK_EQ(call(sys, 9006, 99, 0, 0), 0);
    CHECK_EQ(code, 0);
    CHECK_EQ(call(sys, 9006, 100, 0, 0), 1);
    CHECK_EQ(call(sys, 9006, 95, 0, 0), 1);
    CHECK_EQ(call(sys, 9006, 5, 0, 0), 1);
    hh_sys_free(sys);
}

/* 9.2 rule: started in cycle k, Tn = 1 in cycles k+1 ... k+P. */
static void timer_9006_counts_like_9_2(void)
{
    hh_sys *sys = hh_sys_new(20);
    int c;
    hh_write out[8];
    CHECK_EQ(hh_sys_set_number_mp4111(sys, 2), 0);
    CHECK_EQ(hh_sys_set_mp(sys, 4111, 96, 1, 1), 0); /* 0.1 s at 20 ms -> 5 cycles */
    for (c = 0; c < 9; c++) {
        int32_t running = service_t96(sys);
        CHECK_EQ(running, c >= 1 && c <= 5);
        if (c == 0)
            CHECK_EQ(call(sys, 9006, 96, 0, 0), 0);
        hh_sys_tick(sys);
    }
    CHECK_EQ(hh_sys_service(sys, out, 1), -1); /* two timers configured */
    CHECK_EQ(hh_sys_service(sys, out, 8), 2);
    CHECK(out[1].kind == 'T' && out[1].addr == 97 && out[1].value == 0);
    hh_sys_free(sys);
}

/* Runs `cycles` timer services (results not reported); how many of them found T96 running. */
static int32_t cycles_running_t96(hh_sys *sys, int cycles)
{
    int32_t count = 0;
    while (cycles-- > 0) {
        hh_sys_service(sys, NULL, 0);
        count += hh_sys_timer_running(sys, 96);
    }
    return count;
}

static int32_t run_length(int32_t cycle_time, int64_t mantissa, int32_t decimals, int cycles_unit)
{
    hh_sys *sys = hh_sys_new(cycle_time);
    int32_t count;
    hh_sys_set_number_mp4111(sys, 1);
    hh_sys_set_timer_unit(sys, cycles_unit);
    if (mantissa >= 0)
        hh_sys_set_mp(sys, 4111, 96, mantissa, decimals);
    call(sys, 9006, 96, 0, 0);
    count = cycles_running_t96(sys, 200);
    hh_sys_free(sys);
    return count;
}

static void timer_presets(void)
{
    CHECK_EQ(run_length(20, 125, 3, 0), 7); /* spec 9.3: 0.125 s at 20 ms */
    CHECK_EQ(run_length(20, 1, 1, 0), 5);   /* 0.1 s */
    CHECK_EQ(run_length(20, 2, 0, 0), 100); /* 2 s */
    CHECK_EQ(run_length(30, 1, 1, 0), 4);   /* ceil(100 / 30) */
    CHECK_EQ(run_length(20, 3, 0, 1), 3);   /* cycles unit */
    CHECK_EQ(run_length(20, 0, 0, 0), 0);   /* P = 0: never runs */
    CHECK_EQ(run_length(20, -1, 0, 0), 0);  /* MP4111.96 missing */
}

static void timer_retrigger(void)
{
    int restart;
    for (restart = 1; restart >= 0; restart--) {
        hh_sys *sys = hh_sys_new(20);
        int c, last = -1;
        hh_sys_set_number_mp4111(sys, 1);
        if (!restart) /* restarting is the default (A-34b) */
            hh_sys_set_timer_restart(sys, 0);
        hh_sys_set_mp(sys, 4111, 96, 1, 1); /* 5 cycles */
        for (c = 0; c < 12; c++) {
            if (service_t96(sys))
                last = c;
            if (c == 0 || c == 3)
                call(sys, 9006, 96, 0, 0);
        }
        CHECK_EQ(last, restart ? 8 : 5); /* started in cycles 0 and 3, P = 5 */
        hh_sys_free(sys);
    }
}

static void machine_parameters_9031_9032(void)
{
    hh_sys *sys = hh_sys_new(20);
    int64_t m = 0;
    int32_t d = -1;
    CHECK_EQ(hh_sys_set_mp(sys, 4110, 3, 5, 1), 0); /* 0.5 */
    CHECK_EQ(hh_sys_set_mp(sys, 4110, 3, 5, 10), -1);
    CHECK_EQ(hh_sys_set_mp(sys, 4110, 3, 1000000000000000LL, 0), -1);
    CHECK_EQ(call(sys, 9032, 4110, 3, 0), 0);
    CHECK_EQ(results[0], 5);
    CHECK_EQ(call(sys, 9031, 4110, 3, 12), 0);
    CHECK_EQ(results[0], 0);
    CHECK_EQ(call(sys, 9032, 4110, 3, 0), 0);
    CHECK_EQ(results[0], 12);
    CHECK_EQ(hh_sys_get_mp(sys, 4110, 3, &m, &d), 1);
    CHECK_EQ(m, 12);
    CHECK_EQ(d, 1);
    CHECK_EQ(hh_sys_get_mp(sys, 4110, 4, &m, &d), 0);
    CHECK_EQ(call(sys, 9031, 4110, 4, 1), 1); /* missing MP */
    CHECK_EQ(results[0], 1);
    CHECK_EQ(code, 1);
    CHECK_EQ(call(sys, 9032, 4110, 4, 0), 1);
    CHECK_EQ(results[0], 0);
    CHECK_EQ(code, HH_MODERR_PARAM);
    hh_sys_free(sys);
}

static void run_time_mp_changes_timer_preset(void)
{
    hh_sys *sys = hh_sys_new(20);
    hh_sys_set_number_mp4111(sys, 1);
    hh_sys_set_mp(sys, 4111, 96, 1, 1);
    CHECK_EQ(call(sys, 9031, 4111, 96, 3), 0); /* 0.3 s -> 15 cycles */
    call(sys, 9006, 96, 0, 0);
    CHECK_EQ(cycles_running_t96(sys, 40), 15);
    hh_sys_free(sys);
}

static void status_9035_9036(void)
{
    hh_sys *sys = hh_sys_new(20);
    CHECK_EQ(call(sys, 9036, 7, 42, 0), 0); /* 7: reserved, not range-checked */
    CHECK_EQ(results[0], 0);
    CHECK_EQ(call(sys, 9035, 7, 0, 0), 0);
    CHECK_EQ(results[0], 42);
    CHECK_EQ(call(sys, 9035, 8, 0, 0), 0);
    CHECK_EQ(results[0], 0);
    CHECK_EQ(hh_sys_set_status(sys, 8, -3), 0);
    CHECK_EQ(call(sys, 9035, 8, 0, 0), 0);
    CHECK_EQ(results[0], -3);
    CHECK_EQ(call(sys, 9036, 20, 1, 0), 1); /* wrong number: error result 1, W1022 2 */
    CHECK_EQ(results[0], 1);
    CHECK_EQ(code, 2);
    CHECK_EQ(call(sys, 9036, 2, 11, 0), 1); /* interpolation factor 0..10: error result 2, W1022 1 */
    CHECK_EQ(results[0], 2);
    CHECK_EQ(code, 1);
    CHECK_EQ(call(sys, 9036, 12, 10, 0), 0);
    CHECK_EQ(call(sys, 9036, 10, -1, 0), 0); /* jog limit: -1 cancels, no error */
    CHECK_EQ(hh_sys_set_mp(sys, 7641, 0, 0, 0), 0); /* handwheel interpolation disabled */
    CHECK_EQ(call(sys, 9036, 0, 4, 0), 1);
    CHECK_EQ(results[0], 3);
    CHECK_EQ(code, 6);
    CHECK_EQ(call(sys, 9036, 10, 5000, 0), 0); /* the jog limit is not an interpolation factor */
    CHECK_EQ(hh_sys_set_mp(sys, 7641, 0, 10, 1), 0); /* 1.0 */
    CHECK_EQ(call(sys, 9036, 0, 4, 0), 0);
    CHECK_EQ(call(sys, 9035, -1, 0, 0), 1);
    CHECK_EQ(results[0], 0);
    CHECK_EQ(hh_sys_set_status(sys, HH_STATUS_SIZE, 1), -1);
    hh_sys_free(sys);
}

static void clock_9192_9195(void)
{
    hh_sys *sys = hh_sys_new(20);
    int i;
    int32_t n;
    for (i = 0; i < 49; i++)
        hh_sys_tick(sys);
    CHECK_EQ(hh_sys_time_ms(sys), 980);
    CHECK_EQ(call(sys, 9195, 0, 0, 0), 0);
    CHECK_EQ(results[0], 0);
    hh_sys_tick(sys);
    CHECK_EQ(hh_sys_cycle(sys), 50);
    for (n = -3; n <= -1; n++) {
        CHECK_EQ(call(sys, 9192, n, 0, 0), 0);
        CHECK_EQ(results[0], 1);
    }
    CHECK_EQ(call(sys, 9192, 0, 0, 0), 0); /* PLC counter 1 of 9190, never started */
    CHECK_EQ(results[0], 0);
    CHECK_EQ(call(sys, 9192, 8, 0, 0), 1); /* no such operating time: -1 and the module error */
    CHECK_EQ(results[0], -1);
    CHECK_EQ(code, 1);
    CHECK_EQ(call(sys, 9195, 0, 0, 0), 0);
    CHECK_EQ(results[0], 1);
    hh_sys_free(sys);

    sys = hh_sys_new(300);
    for (i = 0; i < 7; i++)
        hh_sys_tick(sys);
    CHECK_EQ(call(sys, 9192, -2, 0, 0), 0);
    CHECK_EQ(results[0], 2); /* 2.1 s */
    hh_sys_free(sys);
}

static void result_overrides(void)
{
    hh_sys *sys = hh_sys_new(20);
    CHECK_EQ(hh_sys_set_module_result(sys, 9192, 0, 3600), 0);
    CHECK_EQ(hh_sys_set_module_result(sys, 9192, 1, 1), -1);
    CHECK_EQ(hh_sys_set_module_result(sys, 9999, 0, 1), -1);
    CHECK_EQ(hh_sys_set_module_result(sys, 9006, 0, 1), -1); /* no results */
    CHECK_EQ(hh_sys_set_module_result(sys, 9097, 0, 4), 0);
    CHECK_EQ(call(sys, 9192, -1, 0, 0), 0);
    CHECK_EQ(results[0], 3600);
    CHECK_EQ(call(sys, 9097, 0, 0, 0), 0);
    CHECK_EQ(results[0], 4);
    CHECK_EQ(hh_sys_set_module_result(sys, 9192, 0, 7200), 0);
    CHECK_EQ(call(sys, 9192, -1, 0, 0), 0);
    CHECK_EQ(results[0], 7200);
    /* the model still runs: its error status is kept */
    CHECK_EQ(hh_sys_set_module_result(sys, 9032, 0, 11), 0);
    CHECK_EQ(call(sys, 9032, 1, 1, 0), 1);
    CHECK_EQ(results[0], 11);
    hh_sys_clear_module_results(sys, 9192);
    CHECK_EQ(call(sys, 9192, -1, 0, 0), 0);
    CHECK_EQ(results[0], 0);
    CHECK_EQ(call(sys, 9097, 0, 0, 0), 0);
    CHECK_EQ(results[0], 4);
    hh_sys_free(sys);
}

static int call_ctx(hh_sys *sys, int32_t number, int32_t caller, int32_t p0, int32_t p1, int32_t p2, int32_t p3)
{
    int32_t params[4];
    params[0] = p0;
    params[1] = p1;
    params[2] = p2;
    params[3] = p3;
    memset(results, 0x5a, sizeof results);
    code = -99;
    return hh_module_call_ctx(sys, number, caller, params, results, &code);
}

static void context_rule(void)
{
    hh_sys *sys = hh_sys_new(20);
    CHECK_EQ(hh_sys_set_mp(sys, 910, 0, 1001200, 4), 0);
    /* 9032 is submit-only: 20 in the cyclic program, read in a job */
    CHECK_EQ(call_ctx(sys, 9032, HH_CALLER_CYCLIC, 910, 0, 0, 0), 1);
    CHECK_EQ(code, HH_MODERR_NOT_IN_JOB);
    CHECK_EQ(results[0], 0);
    CHECK_EQ(call_ctx(sys, 9032, HH_CALLER_JOB, 910, 0, 0, 0), 0);
    CHECK_EQ(results[0], 1001200);
    /* 9031's error result carries its own number for "not in a submit job" (4), W1022 20 */
    CHECK_EQ(call_ctx(sys, 9031, HH_CALLER_CYCLIC, 910, 0, 5, 0), 1);
    CHECK_EQ(results[0], 4);
    CHECK_EQ(code, HH_MODERR_NOT_IN_JOB);
    /* 9262 names 30 for the wrong context; 9244's error result is -1 */
    CHECK_EQ(call_ctx(sys, 9262, HH_CALLER_CYCLIC, 0, 0, 0, 0), 1);
    CHECK_EQ(code, 30);
    CHECK_EQ(call_ctx(sys, 9244, HH_CALLER_CYCLIC, 0, 0, 0, 0), 1);
    CHECK_EQ(code, HH_MODERR_NOT_IN_JOB);
    CHECK_EQ(results[0], -1);
    /* 9161 is cyclic-only: 24 in a job, and the drives stay disabled */
    hh_sys_set_drives(sys, 0x7, 0x4);
    CHECK_EQ(call_ctx(sys, 9161, HH_CALLER_JOB, 0x3, 0, 0, 0), 1);
    CHECK_EQ(code, HH_MODERR_NOT_CYCLIC);
    CHECK_EQ(call_ctx(sys, 9162, HH_CALLER_JOB, 0, 0, 0, 0), 0);
    CHECK_EQ(results[0], 0);
    CHECK_EQ(call_ctx(sys, 9161, HH_CALLER_CYCLIC, 0x3, 0, 0, 0), 0);
    CHECK_EQ(call_ctx(sys, 9162, HH_CALLER_CYCLIC, 0, 0, 0, 0), 0);
    CHECK_EQ(results[0], 0x3);
    CHECK_EQ(call_ctx(sys, 9159, HH_CALLER_CYCLIC, 0, 0, 0, 0), 0);
    CHECK_EQ(results[0], 0x4);
    hh_sys_free(sys);
}

static void tables_9092_9094(void)
{
    hh_sys *sys = hh_sys_new(20);
    /* no .T table: error 3 (file missing); bad type 2 */
    CHECK_EQ(call_ctx(sys, 9093, HH_CALLER_JOB, 0, 5, 1, 0), 1);
    CHECK_EQ(results[1], 3);
    CHECK_EQ(code, 3);
    CHECK_EQ(call_ctx(sys, 9093, HH_CALLER_JOB, 7, 5, 1, 0), 1);
    CHECK_EQ(results[1], 2);
    CHECK_EQ(hh_sys_set_table(sys, 0, 5, 1, 40000), 0); /* tool 5: R = 4.0000 mm */
    CHECK_EQ(call_ctx(sys, 9093, HH_CALLER_JOB, 0, 5, 1, 0), 0);
    CHECK_EQ(results[0], 40000);
    CHECK_EQ(results[1], 0);
    CHECK_EQ(call_ctx(sys, 9093, HH_CALLER_JOB, 0, 6, 1, 0), 1); /* line not in file */
    CHECK_EQ(results[1], 4);
    CHECK_EQ(call_ctx(sys, 9093, HH_CALLER_JOB, 0, 5, 64, 0), 1); /* bad element */
    CHECK_EQ(results[1], 5);
    CHECK_EQ(call_ctx(sys, 9094, HH_CALLER_JOB, 0, 5, 7, 1200), 0); /* write current life */
    CHECK_EQ(results[0], 0);
    CHECK_EQ(call_ctx(sys, 9093, HH_CALLER_JOB, 0, 5, 7, 0), 0);
    CHECK_EQ(results[0], 1200);
    CHECK_EQ(call_ctx(sys, 9092, HH_CALLER_JOB, 0, 7, 1200, 0), 0); /* search: tool 5 */
    CHECK_EQ(results[0], 5);
    CHECK_EQ(call_ctx(sys, 9092, HH_CALLER_JOB, 0, 7, 99, 0), 1);
    CHECK_EQ(results[0], -1);
    CHECK_EQ(results[1], 6);
    CHECK_EQ(call_ctx(sys, 9093, HH_CALLER_CYCLIC, 0, 5, 1, 0), 1); /* submit-only: error number 1, W1022 20 */
    CHECK_EQ(results[1], 1);
    CHECK_EQ(code, HH_MODERR_NOT_IN_JOB);
    hh_sys_free(sys);
}

static void axes_and_counters(void)
{
    hh_sys *sys = hh_sys_new(500);
    CHECK_EQ(hh_sys_set_axis(sys, 0, 1, 123456), 0);
    CHECK_EQ(hh_sys_set_axis(sys, 2, 1, -5), 0);
    CHECK_EQ(hh_sys_set_axis(sys, 16, 1, 0), -1);
    CHECK_EQ(call(sys, 9038, -1, 0, 0), 0);
    CHECK_EQ(results[0], 0x5);
    CHECK_EQ(call(sys, 9038, 1, 0, 0), 0);
    CHECK_EQ(results[0], 0);
    CHECK_EQ(call(sys, 9038, 0, 10, 0), 1);
    CHECK_EQ(code, 1);
    CHECK_EQ(call(sys, 9038, 20, 0, 0), 1);
    CHECK_EQ(code, 2);
    CHECK_EQ(call(sys, 9049, 0, 2, 0), 0);
    CHECK_EQ(results[0], 123456);
    CHECK_EQ(call(sys, 9049, 0, 4, 0), 1);
    CHECK_EQ(code, 2);
    CHECK_EQ(call(sys, 9190, 0x100, 0, 0), 1); /* only counters 1..8 */
    CHECK_EQ(call(sys, 9190, 0x2, 0, 0), 0);
    hh_sys_tick(sys);
    hh_sys_tick(sys);
    hh_sys_tick(sys);
    CHECK_EQ(call(sys, 9191, 0x2, 0, 0), 0);
    hh_sys_tick(sys);
    CHECK_EQ(call(sys, 9192, 1, 0, 0), 0);
    CHECK_EQ(results[0], 1); /* 1.5 s counted while running */
    hh_sys_free(sys);
}

static void validation_of_machine_modules(void)
{
    hh_sys *sys = hh_sys_new(20);
    /* 9040 / 9042: type 0..4, a D address whose 5 double words fit */
    CHECK_EQ(call(sys, 9040, 100, 4, 0), 0);
    CHECK_EQ(call(sys, 9040, 100, 5, 0), 1);
    CHECK_EQ(code, 1);
    CHECK_EQ(call(sys, 9040, 102, 0, 0), 1);
    CHECK_EQ(call(sys, 9042, 0, 0, 0), 0);
    CHECK_EQ(call(sys, 9042, 6, 0, 0), 1);
    CHECK_EQ(call(sys, 9042, 4096, 0, 0), 0); /* memory size unknown: not checked */
    hh_sys_set_memory_size(sys, 1024);
    CHECK_EQ(call(sys, 9042, 1008, 0, 0), 1); /* D1008..D1024 passes the end */
    CHECK_EQ(call(sys, 9042, 1004, 0, 0), 0); /* D1004..D1020 fits */
    CHECK_EQ(call(sys, 9040, 1008, 0, 0), 1);
    /* 9048: info 0/1 (1), axis -1 or 0..15 (2) */
    CHECK_EQ(call(sys, 9048, -1, 1, 0), 0);
    CHECK_EQ(results[0], 0);
    CHECK_EQ(call(sys, 9048, 0, 2, 0), 1);
    CHECK_EQ(code, 1);
    CHECK_EQ(call(sys, 9048, 16, 0, 0), 1);
    CHECK_EQ(code, 2);
    /* 9095 / 9097 / 9150: error results and codes */
    CHECK_EQ(call(sys, 9095, -1, 0, 0), 1);
    CHECK_EQ(results[0], 1);
    CHECK_EQ(call(sys, 9097, 3, 1, 0), 1);
    CHECK_EQ(results[0], 1);
    CHECK_EQ(code, 2);
    CHECK_EQ(call(sys, 9097, -1, 0, 0), 1);
    CHECK_EQ(results[0], 2);
    CHECK_EQ(call(sys, 9097, 3, 0, 0), 0);
    CHECK_EQ(results[0], 0);
    CHECK_EQ(call(sys, 9150, 1, 0, 0), 1);
    CHECK_EQ(results[0], 2);
    CHECK_EQ(code, 2);
    /* 9102 / 9105: serial interface */
    CHECK_EQ(call(sys, 9102, 2, 0, 0), 1);
    CHECK_EQ(results[0], -1);
    CHECK_EQ(call(sys, 9102, 1, 0, 0), 0);
    CHECK_EQ(results[0], 0);
    CHECK_EQ(call(sys, 9105, 0, 1000, 24), 0);
    CHECK_EQ(call(sys, 9105, 0, 1000, 25), 1);
    CHECK_EQ(call(sys, 9105, 0, 0, 64), 1);
    CHECK_EQ(call(sys, 9105, 2, 0, 1), 1);
    /* 9124 / 9127 */
    CHECK_EQ(call(sys, 9124, 16, 5000, 0), 1);
    CHECK_EQ(results[0], 1);
    CHECK_EQ(code, 1);
    CHECK_EQ(call(sys, 9124, 1, 10001, 0), 1);
    CHECK_EQ(results[0], 3);
    CHECK_EQ(code, 3);
    CHECK_EQ(call(sys, 9124, 1, 10000, 0), 0);
    CHECK_EQ(call(sys, 9127, 0, 4, 0), 1);
    CHECK_EQ(code, 2);
    CHECK_EQ(call(sys, 9127, -1, 0, 0), 1);
    CHECK_EQ(code, 1);
    /* 9144: a second self test in the same cycle is 28, the next cycle may start one */
    CHECK_EQ(call(sys, 9144, 1, 0, 0), 1);
    CHECK_EQ(code, 2);
    CHECK_EQ(call(sys, 9144, 10, 3, 0), 1);
    CHECK_EQ(call(sys, 9144, 11, 2, 0), 0);
    CHECK_EQ(call(sys, 9144, 0, 0, 0), 0);
    CHECK_EQ(results[0], 0);
    CHECK_EQ(call(sys, 9144, 0, 0, 0), 1);
    CHECK_EQ(code, 28);
    hh_sys_tick(sys);
    CHECK_EQ(call(sys, 9144, 0, 0, 0), 0);
    /* 9194, 9231, 9244 */
    CHECK_EQ(call(sys, 9194, -4, 60, 100), 1);
    CHECK_EQ(call(sys, 9194, 7, 60, 100), 0);
    CHECK_EQ(call(sys, 9194, 0, 60, -1), 1);
    CHECK_EQ(call(sys, 9231, 9, 0, 0), 1);
    CHECK_EQ(code, 1);
    CHECK_EQ(call(sys, 9231, 8, -30001, 0), 1);
    CHECK_EQ(code, 2);
    CHECK_EQ(call(sys, 9231, 0, 30000, 0), 0);
    CHECK_EQ(call(sys, 9244, 0, 8, 0), 1);
    CHECK_EQ(results[0], -1);
    CHECK_EQ(code, 3);
    CHECK_EQ(call(sys, 9244, -1, 0, 0), 1);
    CHECK_EQ(code, 2);
    /* 9260, 9261, 9429 */
    CHECK_EQ(call(sys, 9260, 1, 0, 0), 1);
    CHECK_EQ(code, 2);
    CHECK_EQ(call(sys, 9260, -1, 0, 0xff), 0);
    CHECK_EQ(results[0], 0);
    CHECK_EQ(call(sys, 9261, (int32_t)0x80000000u, 1, 0), 0);
    CHECK_EQ(call(sys, 9261, 3, 1, 0), 1);
    CHECK_EQ(code, 30);
    CHECK_EQ(call(sys, 9429, 0, 0, 3), 0);
    CHECK_EQ(results[0], 2);
    CHECK_EQ(results[3], 0);
    CHECK_EQ(call(sys, 9429, 1, 0, 0), 1);
    CHECK_EQ(call(sys, 9429, 0, 0, 4), 1);
    CHECK_EQ(call(sys, 9429, 0, -1, 1), 1);
    CHECK_EQ(code, 1);
    hh_sys_free(sys);
}

static void invalid_context(void) { CHECK(hh_sys_new(0) == NULL); }

void run_module_tests(void)
{
    RUN(module_table);
    RUN(context_rule);
    RUN(tables_9092_9094);
    RUN(axes_and_counters);
    RUN(validation_of_machine_modules);
    RUN(unknown_and_stub_calls);
    RUN(timer_9006_needs_numbermp4111);
    RUN(timer_9006_counts_like_9_2);
    RUN(timer_presets);
    RUN(timer_retrigger);
    RUN(machine_parameters_9031_9032);
    RUN(run_time_mp_changes_timer_preset);
    RUN(status_9035_9036);
    RUN(clock_9192_9195);
    RUN(result_overrides);
    RUN(invalid_context);
}
