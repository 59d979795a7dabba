"""The front end: a HEIDENHAIN project on disk becomes one resolved IR program.

In: the main `.src` file and the project options (configuration, DEFINEs, include folders,
profile). Stages, in order: `sources` (find and read files) -> `preprocess` (DEFINE values,
`#if`, INCLUDE, line map) -> `parse` (lark grammars in `grammars/` -> the typed syntax tree of
`ast`) -> `load` (every file of the project in the control's order) -> `resolve` (symbols,
operands, labels and calls -> `transpiler.ir.Program`); `pipeline` runs them in order.
Out: an `ir.Program` and the diagnostics. Must not know: back ends, executors, scenarios.
"""
