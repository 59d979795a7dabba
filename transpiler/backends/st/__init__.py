"""The ST back end: translates one resolved `transpiler.ir.Program` into an IEC 61131-3 Structured Text project.

It runs in passes over the IR, each module doing one job: `liveness` finds, per routine and op, which registers
(LA, WA, SA, X) hold a value still read later; `names` hands out legal, unique IEC names and records every rename;
`layout` decides the global variable of every operand (named BOOL/SINT/INT/DINT variables, arrays where byte/word/
double operands overlap or are indexed); `structure` recovers IF/ELSE, WHILE, REPEAT, EXIT, RETURN and CASE from
the jumps of each routine, falling back to a state machine when they are irreducible; while it walks the ops the
symbolic executor (`symbolic`, built from `routine`, `inflight`, `operands`, `arith`, `stackops` and the `ops_*`
modules) turns accumulators, the data stack and brackets into the typed expressions of `exprs` and builds the
statement tree of `stmt`, which `passes` cleans up and `printer` alone turns into ST text; `backend` assembles the POUs, the helpers of `library`, types, globals and the configuration into an
`IecProject` (with the layout, names, fallbacks and presets the reports need), and `writer` prints it as ST text
(`check` runs external syntax checkers over that text). Out comes the `StResult` / ST text and nothing else: this
package imports only transpiler.diagnostics, .language, .ir, .frontend and the IEC model of transpiler.backends,
and knows nothing of the executors, scenarios, co-simulation or the CLI.
"""
