/* hh_modules.h - the shared PLC module table (spec 14, ASSUMPTION A-46) and the simulated
 * system context the modules act on (clock, machine parameters, status table, the
 * additional timers T96-T999 of module 9006, spec 9.4 / A-37 / 17b.10).
 *
 * Calling convention (spec 14.1): the caller pops nparams 32-bit values (params[0] = the
 * first parameter pushed), calls hh_module_call, pushes the nresults results so that the
 * first PL gets results[0], and copies the return value into M4203 (M3171 on tnc407).  When
 * the return value is 1 it also writes *error_code to W1022 (W1022 holds the code of the
 * last module call that FAILED, so it is not written on success).
 *
 * What is modelled (everything else in the catalogue is a stub: results 0, M4203 = 0):
 *  9006  start additional timer Tn (1 parameter, 0 results).  Valid n: 96 ... 95 +
 *        NUMBERMP4111 (NUMBERMP4111 = number of additional timers, default 0, at most 904);
 *        any other n -> module error, code HH_MODERR_PARAM.  The start takes effect in the
 *        next hh_sys_service: the counting rule of spec 9.2 (rem := P, then count down; Tn = 1
 *        while rem > 0), P from the run-time value of MP4111.n (seconds -> ceil(t / cycle
 *        time) with exact decimal arithmetic, spec 9.3; or cycles, see hh_sys_set_timer_unit).
 *        A missing MP4111.n gives P = 0 (the timer never runs) - an assumption.
 *  9031  overwrite the run-time copy of MP number.index (3 parameters: number, index, value
 *        as an integer with the decimal point removed, i.e. the new mantissa at the decimal
 *        position of the stored value; 1 result: error).  An MP not set with hh_sys_set_mp ->
 *        result 1, module error, code 1.  Not modelled: error 2 (value range - the ranges are
 *        unknown), 3, 4 (submit-job context), 5 (strobe context): every MP is writable.
 *  9032  read the run-time value of MP number.index (2 parameters, 1 result: the mantissa,
 *        i.e. the value with the decimal point removed, saturated to int32).  Missing MP ->
 *        result 0, module error, code 1.  The submit-job restriction is not checked.
 *  9035  read status information (1 parameter: type; 1 result: value) and
 *  9036  write status information (2 parameters: number, value; 1 result: error).  The real
 *        status numbers are not documented in the sources, so both address one table of
 *        HH_STATUS_SIZE entries, all 0 at start (9035 reads what 9036 or hh_sys_set_status
 *        wrote).  A number outside the table -> result 0 (9035) / 1 (9036), module error, code 1.
 *  9192  read an operating time (1 parameter: number; 1 result: seconds).  -3 control on,
 *        -2 machine on, -1 program run: all = whole seconds of simulated time since cycle 0
 *        (floor(cycle * cycle_time_ms / 1000)); 0..7 the PLC counters of 9190/9191.  Any other
 *        number -> -1 (the documented error answer) and module error code 1.
 *  9195  system time (0 parameters; 1 result): whole seconds of the simulated clock, same
 *        value as 9192 -3 (the simulated clock starts at 0).
 *  9038/9049 axis information / REF position from hh_sys_set_axis; 9092/9093/9094 tables from
 *        hh_sys_set_table (error numbers 2..6 of the manual, also pulled as the error result);
 *        9159/9161/9162/9169 drives (9162 = available AND enabled); 9190/9191 start/stop the 8 PLC
 *        operating-hours counters that 9192 0..7 reads (other numbers: -1 and module error 1).
 *  Parameter validation with the documented error codes (the machine-dependent results stay 0, the
 *        assumptions are named in the module table's rows): 9036 (numbers 0..19, factors 0..10, MP7641),
 *        9040/9042 (type, D address and block fit), 9048, 9095, 9097, 9102, 9105, 9124, 9127, 9144 (self
 *        test active to the end of its cycle: 28), 9150, 9194, 9231, 9244, 9260, 9261 (only the submit queue
 *        K$80000000), 9429 (status 2: no NC program runs).  A row may name its own code for the wrong
 *        calling context (9262/9263: 30) and its own error result then (9093/9094: 1, 9095: 7, 9097: 6,
 *        9192/9244: -1).
 * The table rows (signatures, kind, calling context, profiles) are generated from the Python table into
 * hh_module_table.h.  Every other row runs the stub rule of A-46 (results 0, no error).  The pure
 * modules (9019, 9050-9054, 9070) need PLC memory, so the executors implement them, not the shim.
 * hh_module_call_ctx applies the calling-context rule (codes 20 / 24).
 *
 * Scenario `module_results` overrides (hh_sys_set_module_result) replace the results of a
 * module after its model ran; the module's effects and its error status are kept.
 */
#ifndef HH_MODULES_H
#define HH_MODULES_H

#include "hh_common.h"

typedef struct hh_sys hh_sys;

/* hh_module_info results */
enum { HH_MODULE_UNKNOWN = 0, HH_MODULE_STUB = 1, HH_MODULE_MODELLED = 2 };

/* W1022 error codes written by the models (assumption: the real codes are not documented
 * except for 9031, whose code is its error result). */
enum { HH_MODERR_PARAM = 1 };
/* W1022 codes of the calling context (documented iTNC/TNC 426 convention). */
enum { HH_MODERR_NOT_IN_JOB = 20, HH_MODERR_NOT_CYCLIC = 24 };

/* Rows of the generated table hh_module_table.h. */
enum { HH_KIND_PURE = 0, HH_KIND_DATA = 1, HH_KIND_MACHINE = 2 };
enum { HH_CTX_ANY = 0, HH_CTX_CYCLIC = 1, HH_CTX_SUBMIT = 2 };
/* Who calls: the context rule is checked only for CYCLIC and JOB callers. */
enum { HH_CALLER_ANY = 0, HH_CALLER_CYCLIC = 1, HH_CALLER_JOB = 2 };

#define HH_AXES 16
#define HH_HOUR_COUNTERS 8
#define HH_TABLE_ELEMENTS 63

#define HH_MODULE_MAX_PARAMS 8
#define HH_MODULE_MAX_RESULTS 8
#define HH_STATUS_SIZE 256
#define HH_EXTRA_TIMER_FIRST 96
#define HH_EXTRA_TIMER_LAST 999
#define HH_EXTRA_TIMER_COUNT (HH_EXTRA_TIMER_LAST - HH_EXTRA_TIMER_FIRST + 1)

/* Table lookup; nparams/nresults may be NULL (they are set to 0 for an unknown number). */
int hh_module_info(int32_t number, int32_t *nparams, int32_t *nresults);
/* Metadata of a table entry: kind HH_KIND_*, context HH_CTX_*, strobe-bound, profile bit mask, index of
 * the error result (-1 none).  0 for an unknown number (outputs untouched), else 1. */
int hh_module_meta(int32_t number, int32_t *kind, int32_t *context, int32_t *strobe, int32_t *profiles,
                   int32_t *error_result);
/* Purpose text of a table entry for reports, "" for an unknown number. */
const char *hh_module_purpose(int32_t number);
/* Enumerate the table: entries 0 .. hh_module_count()-1. */
int32_t hh_module_count(void);
int32_t hh_module_number_at(int32_t i);

/* Runs module `number`: reads params[0..nparams-1], writes results[0..nresults-1].
 * Returns the module error status (0 or 1, the value for M4203) and sets *error_code (the
 * W1022 value when the status is 1, else 0); -1 for a number without table entry (nothing
 * happens: the caller reports E-RT-MODULE or applies its own stub rule). */
int hh_module_call(hh_sys *sys, int32_t number, const int32_t *params, int32_t *results, int32_t *error_code);

/* As hh_module_call, with the calling context rule: a submit-only module called by HH_CALLER_CYCLIC, or
 * a cyclic-only module called by HH_CALLER_JOB, does nothing, returns 1 with code 20 / 24, results 0
 * (the error result, if the module has one, = the code).  hh_module_call is HH_CALLER_ANY. */
int hh_module_call_ctx(hh_sys *sys, int32_t number, int32_t caller, const int32_t *params, int32_t *results,
                       int32_t *error_code);

/* NULL when cycle_time_ms <= 0 or memory is exhausted. */
hh_sys *hh_sys_new(int32_t cycle_time_ms);
void hh_sys_free(hh_sys *sys);
/* A deep copy with the same configuration, clock and model state (free it with hh_sys_free). */
hh_sys *hh_sys_clone(const hh_sys *sys);

/* Machine parameter number.index = mantissa * 10^-decimals (0.125 -> 125, 3), as loaded
 * from the MP file or the scenario; 9031 later overwrites this run-time value.  0, or -1 for
 * decimals outside 0..9, |mantissa| >= 10^15, or no memory. */
int hh_sys_set_mp(hh_sys *sys, int32_t number, int32_t index, int64_t mantissa, int32_t decimals);
/* Run-time value of an MP: 1 and the outputs set, 0 when the MP is not set. */
int hh_sys_get_mp(const hh_sys *sys, int32_t number, int32_t index, int64_t *mantissa, int32_t *decimals);
/* NUMBERMP4111 (OEM.SYS): how many additional timers exist, 0..HH_EXTRA_TIMER_COUNT; 0 or -1. */
int hh_sys_set_number_mp4111(hh_sys *sys, int32_t count);
/* Unit of MP4111 (ASSUMPTION A-35, key timer_unit): 0 seconds (default), 1 PLC cycles. */
void hh_sys_set_timer_unit(hh_sys *sys, int32_t cycles);
/* A-34b timer_restart_while_running: 1 (default) a start restarts a running timer; 0 it is ignored. */
void hh_sys_set_timer_restart(hh_sys *sys, int32_t restart);
/* Status table entry (the value 9035 reads); 0 or -1 for a number outside the table. */
int hh_sys_set_status(hh_sys *sys, int32_t number, int32_t value);
/* Scenario override of result `index` of module `number`; 0, or -1 for an unknown module,
 * an index >= its result count, or no memory. */
int hh_sys_set_module_result(hh_sys *sys, int32_t number, int32_t index, int32_t value);
void hh_sys_clear_module_results(hh_sys *sys, int32_t number);

/* Axis `axis` (0..HH_AXES-1): active flag (9038 info 0) and actual REF position in 0.0001 mm (9049). 0 / -1. */
int hh_sys_set_axis(hh_sys *sys, int32_t axis, int32_t active, int32_t position);
/* Size in bytes of the PLC's B/W/D memory (9040/9042 refuse a block that does not fit); 0 = unknown. */
void hh_sys_set_memory_size(hh_sys *sys, int32_t bytes);
/* Drives: bit mask of ready power stages (9162 reads available AND the mask 9161 enabled) and the
 * early warning 9159 reads. */
void hh_sys_set_drives(hh_sys *sys, int32_t available, int32_t switching_off);
/* Element of a table selected for program run (type 0 .T, 1 .D, 2 .TCH): what 9092/9093 read and 9094
 * writes.  A line exists once any of its elements is set.  0, or -1 for a bad type/element or no memory. */
int hh_sys_set_table(hh_sys *sys, int32_t type, int32_t line, int32_t element, int32_t value);

/* Advance the simulated clock by one cycle (scenario step 5). */
void hh_sys_tick(hh_sys *sys);
int64_t hh_sys_cycle(const hh_sys *sys);
int64_t hh_sys_time_ms(const hh_sys *sys);

/* Phase 3 timer service of the additional timers (spec 9.2 rule).  Writes the running value
 * of EVERY configured additional timer (T96 ... T(95+NUMBERMP4111)) to out, like the 9.2
 * service rewrites every T(n+48): a PLC write to such an operand is overwritten.  Returns the
 * number of writes, or -1 when max_out < NUMBERMP4111 (the service still happened).  With
 * out == NULL nothing is reported and 0 is returned. */
int hh_sys_service(hh_sys *sys, hh_write *out, int max_out);
/* 1 while additional timer Tn runs, else 0 (also for n outside 96..999). */
int hh_sys_timer_running(const hh_sys *sys, int32_t n);

#endif
