"""Verification: the evidence behind a port.

In: an IR program, the transpiled ST and scenario files. `scenario` loads and binds the scenario
format; `stimulus` turns a scenario into per-cycle writes and NC jobs and checks expectations;
`simulate` runs the reference interpreter under a scenario; `cosim` drives the interpreter and an
ST executor in lockstep and compares every compared operand after every cycle; `equiv` runs the
co-simulation over scenarios and random stimulus, shrinks divergences and gives the verdict;
`source_coverage` combines the runs' coverage of the original per instruction and per source line, and
`coverage_export` writes it as Cobertura XML and LCOV for CI tools;
`traces` records CSV/VCD traces. Out: typed results and verdicts. Must not know: the command line
(argument parsing and printing live in `transpiler.cli`).
"""
