"""The ST backend: turns the IR program into an IecProject (POUs, types, globals, configuration) plus the facts the report needs."""

from __future__ import annotations

import dataclasses
import itertools
import re
from decimal import Decimal
from typing import Mapping

from transpiler.diagnostics import Diagnostics, Span
from transpiler.backends.iec_model import (ArrayDim, Configuration, DataType, IecProject, IecVar, Pou, ProgramInstance, SourceRange,
                         Task, VarSection)
from transpiler.ir import CallTarget, DataRow, Operand, Program
from transpiler.records import replaced
from transpiler.language.presets import COUNTER_MP, TIMER_MP, load_presets
from transpiler.frontend.flow import RoutineBodies
from transpiler.backends.st import exprs as E
from transpiler.backends.st import jobs, library, modcalls
from transpiler.backends.st.dialect import DEFAULT_TARGET, TARGETS, Dialect
from transpiler.backends.st.layout import GROUP_TITLES, MEM_TYPE, GlobalVar, Layout, group_title
from transpiler.backends.st.liveness import Liveness
from transpiler.backends.st.interfaces import Dynamic, Effect, StackAnalysis
from transpiler.backends.st import passes, printer, simplify
from transpiler.backends.st import stmt as S
from transpiler.backends.st.names import POU_KEY_PREFIX, RESERVED, TEMP_PREFIX, NameTable, legalise
from transpiler.backends.st.structure import JUMPS, NotStructured, RoutineInfo, Structurer, state_machine
from transpiler.backends.st.routine import REG_TYPES, AccessorPool, Emitter, RoutineContext, Unsupported, tag
from transpiler.backends.st.stackops import SLOT_TYPES, StaticStack
from transpiler.backends.st.symbolic import Executor

# A name in a POU body; the part after a dot (`ML_ax.inpos`, `inst.Q`) is a member, no global.
_IDENT = re.compile(r"(?<![A-Za-z0-9_.])[A-Za-z_][A-Za-z0-9_]*")
_COMMENT = re.compile(r"\(\*.*?\*\)", re.S)


@dataclasses.dataclass(frozen=True)
class Fallback:
    pou: str
    reason: str
    span: Span


@dataclasses.dataclass(frozen=True)
class StResult:
    project: IecProject
    layout: Layout
    names: NameTable
    fallbacks: tuple[Fallback, ...]
    untranslated: tuple[tuple[Span, str], ...]
    pou_of_routine: Mapping[tuple[int, int], str]
    timers: tuple[int, ...]
    counters: tuple[int, ...]
    presets: Mapping[str, int]          # preset variable -> value in cycles
    preset_vars: Mapping[tuple[int, int], str]   # (MP number, index) -> preset variable
    # POUs that still move the emulated data stack, with the reason its depth is not static there
    dynamic_stack: tuple[tuple[str, str, Span], ...] = ()
    # Submit jobs: (job number, POU of the job subprogram, where its label is), and the POU that runs them
    submit_jobs: tuple[tuple[int, str, Span], ...] = ()
    jobs_program: str | None = None
    # PLC data tables: row key (`MP_Data.tab:DG_x`) -> (global holding the row's value, its IEC type, the row)
    data_vars: Mapping[str, tuple[str, str, DataRow]] = dataclasses.field(default_factory=dict)


class StBackend:
    def __init__(self, program: Program, diags: Diagnostics, mp: Mapping[tuple[int, int], Decimal] | None = None,
                 project_name: str | None = None, mp_file: str | None = None,
                 dialect: Dialect = TARGETS[DEFAULT_TARGET]):
        """`dialect` is the target's table: how the POU bodies reference globals and read bits (dialect.py)."""
        self.program = program
        self.diags = diags
        self.dialect = dialect
        self.mp = dict(mp or {})
        self.mp_file = mp_file
        self.semantics = program.semantics
        self.main_name_wanted = project_name or re.sub(r"\.src$", "", program.main.path.split("/")[-1], flags=re.I)
        self.names = NameTable()
        self.helpers_used: set[str] = set()
        self.fallbacks: list[Fallback] = []
        self.untranslated: list[tuple[Span, str]] = []
        self.kfields: dict[str, str] = {}          # KFIELD key -> name of its constant array
        self.types: list[DataType] = []
        self._taken_names: set[str] | None = None    # see _names_taken_by_globals_and_pous
        self._taken_globals = 0

    # ---- naming

    def _reserve_pou_names(self, helpers: Mapping[str, Pou]) -> None:
        for name in [*helpers, "HH_TIMER", "HH_COUNTER", jobs.QUEUE_FB, jobs.QUEUE_TYPE, jobs.QUEUE_INTS,
                     jobs.QUEUE_FLAGS]:
            self.names.reserve(name, f"lib:{name}")
        self.main_pou = self.names.name(f"{POU_KEY_PREFIX}main", self.main_name_wanted)
        self.pou_names: dict[tuple[int, int], str] = {}
        for r in self.program.routines:
            self.pou_names[r.key] = self.names.name(f"{POU_KEY_PREFIX}{r.file}:{r.index}", r.label)

    def _name_instances(self) -> None:
        """One instance per subprogram (its markers are the program's, so every call shares it), named after it
        as the module call blocks are (`Clamp_axis_1`); named after the layout, so that the program's own symbols
        keep their names where one looks like an instance's."""
        self.instance_names: dict[tuple[int, int], str] = {
            key: self.names.name(f"inst:{key}", f"{name}_1") for key, name in self.pou_names.items()}

    # ---- build

    def build(self) -> StResult:
        helpers = library.helper_pous()
        self._reserve_pou_names(helpers)
        layout = Layout(self.program, self.names, self.helpers_used.add, self.dialect)
        self.layout = layout
        self._name_instances()
        self.bodies = RoutineBodies.of(self.program)
        self.liveness = Liveness(self.program, self.bodies)
        self.stack: tuple[str, str] | None = None
        self.stack_analysis = StackAnalysis(self.program, _module_effect, bodies=self.bodies)
        self._stack_depth_read()
        self.modules_used: set[int] = set()
        self.interface_names: dict[tuple[int, int], tuple[tuple[str, ...], tuple[str, ...]]] = {}
        self.real_stack_users: dict[str, tuple[int, int]] = {}
        self.current_key: tuple[int, int] = (0, 0)
        self.job_plan = jobs.plan_jobs(self.program, self.bodies)
        self.job_queue: str | None = None
        # Routine entries by file: op indices are per file, so one dict keyed by index alone let the routines of
        # different files that start at the same index overwrite each other.
        entries_by_file: dict[int, dict[int, CallTarget]] = {}
        for r in self.program.routines:
            entries_by_file.setdefault(r.file, {})[r.index] = r
        pous: dict[tuple[int, int], Pou] = {}
        routine_keys = [(0, 0)] + [r.key for r in self.program.routines]
        self.calls: dict[tuple[int, int], set[tuple[int, int]]] = {}
        self.file_jumps: dict[int, list[int]] = {}
        for key in routine_keys:
            pous[key] = self._routine(key, entries_by_file.get(key[0], {}))
        presets = self._presets(layout)
        main = pous.pop((0, 0))
        main = self._with_services(main, layout, self._data_load(layout))
        user_pous = [self._bit_accessor_pou(kind) for kind in sorted(layout.bit_access)] + self._order(pous)
        lib = [p for name, p in helpers.items() if name in self._helper_closure()]
        lib += modcalls.library_pous(self.modules_used, self.semantics.profile.string_len)
        fbs = []
        if layout.timers:
            fbs.append(library.timer_fb(self.semantics))
        if layout.counters:
            fbs.append(library.counter_fb(self.semantics))
        job_types: list[DataType] = []
        if self.job_queue is not None:
            fbs.append(jobs.queue_fb(self.semantics["submit_model"]))
            job_types = jobs.queue_types(self.semantics["submit_model"])
        job_program = self._jobs_program(layout) if self.job_plan.used else None
        types = tuple(self._types(layout)) + tuple(job_types)
        config = self._configuration(layout, job_program)
        # Only the POUs translated from the program read globals: the library ones use their own variables
        # (and a FUNCTION may not declare VAR_EXTERNAL).
        globals_by_upper = {v.name.upper(): (v, s.comment) for s in config.globals for v in s.vars}
        area_order = {area: n for n, area in enumerate(dict.fromkeys(a for _, a in globals_by_upper.values()))}
        declarations: dict[str, IecVar] = {}       # (one VAR_EXTERNAL record per global serves every POU)
        program_pous = [_with_externals(p, globals_by_upper, area_order, declarations)
                        for p in user_pous + [main] + ([job_program] if job_program is not None else [])]
        project = IecProject(self.main_pou, types, tuple(lib + fbs + program_pous), config,
                             header_comment=self._header())
        return StResult(project, layout, self.names, tuple(self.fallbacks), tuple(self.untranslated),
                        {**self.pou_names, (0, 0): self.main_pou},
                        tuple(layout.timers), tuple(layout.counters), presets, self.preset_vars,
                        self._dynamic_stack(), self._submit_jobs(),
                        job_program.name if job_program is not None else None, self.data_vars)

    def _submit_jobs(self) -> tuple[tuple[int, str, Span], ...]:
        files = self.program.files
        return tuple((number, self.pou_names[key], files[key[0]].ops[key[1]].span)
                     for key, number in sorted(self.job_plan.numbers.items(), key=lambda item: item[1]))

    def _stack_depth_read(self) -> None:
        """A program that reads the data-stack depth (PLC module 9019) keeps every subprogram's stack in the emulated
        stack: with parameters in VAR_INPUTs no stack pointer would hold the depth the control reports."""
        if modcalls.STACK_DEPTH not in self.program.modules_used:
            return      # (the program's list of the modules it calls: no pass over every op)
        reads = [op for f in self.program.files for op in f.ops
                 if op.call is not None and op.call.is_module and op.call.module == modcalls.STACK_DEPTH]
        if not reads:
            return
        span = reads[0].span
        why = Dynamic(f"the program reads the data-stack depth (PLC module 9019 at {span.file}:{span.line})", span)
        self.stack_analysis.interfaces.clear()
        for key in [(0, 0)] + [r.key for r in self.program.routines]:
            self.stack_analysis.dynamic.setdefault(key, why)

    def _dynamic_stack(self) -> tuple[tuple[str, str, Span], ...]:
        out = []
        for pou, key in sorted(self.real_stack_users.items()):
            why = self.stack_analysis.dynamic.get(key)
            if why is not None:
                out.append((pou, why.reason, why.span))
        return tuple(out)

    def _interface(self, key: tuple[int, int]):
        """The stack interface of a routine with a static stack depth (None: it keeps the emulated stack)."""
        iface = self.stack_analysis.interfaces.get(key)
        if iface is not None and key == (0, 0):
            # What the main program leaves on the stack is dropped at the end of the cycle: no outputs.
            iface = dataclasses.replace(iface, results=())
        return iface

    def _names_of_interface(self, key: tuple[int, int]) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """VAR_INPUT and VAR_OUTPUT names: legal, distinct, and no global or POU name (a local would hide it)."""
        if key not in self.interface_names:
            iface = self._interface(key)
            taken = self._names_taken_by_globals_and_pous()
            chosen_upper: set[str] = set()
            chosen: list[str] = []
            for wanted, _ in iface.params + iface.results:
                name = legalise(wanted)[0]
                base, n = name, 2
                while name.upper() in taken or name.upper() in chosen_upper \
                        or name.upper().startswith(TEMP_PREFIX.upper()) and name[3:].isdigit():
                    name = f"{base}_{n}"
                    n += 1
                chosen_upper.add(name.upper())
                chosen.append(name)
            k = len(iface.params)
            self.interface_names[key] = (tuple(chosen[:k]), tuple(chosen[k:]))
        return self.interface_names[key]

    def _names_taken_by_globals_and_pous(self) -> set[str]:
        """Upper-case names a VAR_INPUT or VAR_OUTPUT may not take: the reserved words, every POU and instance
        name and every global declared so far. Globals are only ever added (in dict order), so the set grows
        with the newest ones instead of being rebuilt for each routine (thousands of routines, as many globals)."""
        if self._taken_names is None:
            self._taken_names = set(RESERVED) | {n.upper() for n in self.pou_names.values()}
            self._taken_names |= {n.upper() for n in self.instance_names.values()} | {self.main_pou.upper()}
            self._taken_globals = 0
        globals_ = self.layout.globals
        if len(globals_) > self._taken_globals:
            self._taken_names.update(g.upper() for g in itertools.islice(globals_, self._taken_globals, None))
            self._taken_globals = len(globals_)
        return self._taken_names

    def _header(self) -> str:
        p = self.program
        text = (f"Generated by hh2iec from {p.main.path} (profile {p.semantics.profile.name}).\n"
                f"Source files: {', '.join(p.source_files)}.\n")
        if self.mp_file:
            text += f"Timer and counter presets from the machine parameters of {self.mp_file}.\n"
        elif self.mp:
            text += "Timer and counter presets from machine parameters given to the translation.\n"
        elif self.preset_vars:
            text += "No machine-parameter file: every timer and counter preset is 0.\n"
        return text + "HEIDENHAIN symbol names are kept; every block carries its source file and line."

    def _helper_closure(self) -> set[str]:
        todo = list(self.helpers_used)
        done: set[str] = set()
        while todo:
            h = todo.pop()
            if h in done:
                continue
            done.add(h)
            todo.extend(library.HELPER_DEPENDENCIES.get(h, ()))
        return done

    def _register(self, reg: str) -> str:
        """How the POU bodies name the variable of register `reg` (declared on first use)."""
        typ, wanted, comment = REG_TYPES[reg]
        return self.layout.ref(self.layout.add_register(f"reg:{reg}", wanted, typ, comment))

    def _stack_names(self) -> tuple[str, str]:
        """The data stack array and its pointer, as the POU bodies name them (declared on first use)."""
        if self.stack is None:
            words = int(self.semantics["data_stack_words"])
            tname = self.names.name("type:stack", "T_HH_STACK")
            self.types.append(DataType(tname, "array", "INT", (ArrayDim(0, words + 1),),
                                       comment="data stack of 16-bit words (A-19)"))
            arr = self.layout.add_register("stack", "HH_STACK", tname, "data stack (PS/PL), 16-bit words")
            sp = self.layout.add_register("sp", "HH_SP", "INT", "data stack pointer (number of words)")
            self.stack = (self.layout.ref(arr), self.layout.ref(sp))
        self.real_stack_users.setdefault(self.pou_names.get(self.current_key, self.main_pou), self.current_key)
        return self.stack

    def _kfield(self, o: Operand) -> str:
        key = f"kf:{o.text}:{','.join(map(str, o.kfield))}"
        if key not in self.kfields:
            tname = self.names.name(f"type:{key}", f"T_KF_{o.text}")
            name = self.names.name(key, f"KF_{o.text}")
            self.types.append(DataType(tname, "array", "DINT", (ArrayDim(0, len(o.kfield) - 1),),
                                       comment=f"constant field {o.text} (KFIELD)"))
            self.kfields[key] = name
            init = "[" + ", ".join(str(v) for v in o.kfield) + "]"
            self.layout.globals[name] = GlobalVar(name, tname, "kfield", initial=init, comment=f"KFIELD {o.text}")
        return self.layout.ref(self.kfields[key])

    def _module_call(self, ex: Executor, op, live: frozenset[str]) -> None:
        in_job = self.layout.ref(self.layout.add_register("in_job", modcalls.IN_JOB_VAR, "BOOL",
                                                           "TRUE while a submit job runs"))
        # 9050 writes the decimal character of MP7280 (0 comma, else point), as the interpreter does.
        point = "," if self.mp.get((7280, 0)) == 0 else "."
        modcalls.emit_module_call(ex, op, live, in_job, self.modules_used, point)

    def _routine(self, key: tuple[int, int], file_entries: dict[int, CallTarget]) -> Pou:
        """One POU; `file_entries` are the routine entries of the routine's file (by op index)."""
        # Kept whole (~80 lines): the closures below share this routine's temporaries, callees and accessors.
        program = self.program
        is_main = key == (0, 0)
        entry = CallTarget(0, 0, "<main>") if is_main else file_entries[key[1]]
        file = program.files[key[0]]
        body = self.bodies(entry)       # (in op order)
        temps: list[tuple[str, str]] = []

        def scratch(name: str) -> bool:
            """Registers and this routine's temporaries: assigning one writes no operand."""
            return name in self.layout.register_vars or any(name == t.upper() for t, _ in temps)

        emitter = Emitter(scratch)
        callees: set[tuple[int, int]] = set()
        pou_name = self.main_pou if is_main else self.pou_names[key]

        def temp(typ: str) -> str:
            name = f"{TEMP_PREFIX}{len(temps) + 1}"
            temps.append((name, typ))
            return name

        def instance(typ: str) -> str:
            base, count = typ.removeprefix("HH_"), sum(1 for _, t in temps if t == typ) + 1
            while self.names.taken(f"{base}_{count}"):      # another POU's instance of the same block
                count += 1
            name = self.names.name(f"fb:{key}:{len(temps)}", f"{base}_{count}")
            temps.append((name, typ))
            return name

        def live_after(i: int) -> frozenset[str]:
            return self.liveness.at(key, i + 1) if i + 1 < len(file.ops) else frozenset()

        def call_name(target: CallTarget) -> str:
            callees.add(target.key)
            return self.instance_names[target.key]

        iface = self._interface(key)
        slots: dict[tuple[int, str], str] = {}
        executors: list[Executor] = []

        def slot(depth: int, kind: str) -> str:
            if (depth, kind) not in slots:
                slots[(depth, kind)] = f"stack{depth}_{kind}"
            return slots[(depth, kind)]

        def executor() -> Executor:
            static = None
            if iface is not None:
                params, results = self._names_of_interface(key)
                static = StaticStack(iface, params, results, slot)
            executors.append(Executor(ctx, static))
            return executors[-1]

        def interface_call(op, i: int, live: frozenset[str]) -> bool:
            target = op.call
            callee = self._interface(target.key) if target is not None and not target.is_module else None
            if callee is None or callee.empty:
                return False
            callees.add(target.key)
            params, results = self._names_of_interface(target.key)
            executors[-1].call_interface(self.instance_names[target.key], callee, params, results, live,
                                         tag(file.ops[i].span))
            return True

        accessors = AccessorPool()
        ctx = RoutineContext(self.layout, emitter, live_after, self._register, self.helpers_used.add, temp,
                             self._kfield, self._stack_names, self._module_call, self.semantics, accessors.pick,
                             self.job_plan.routine(key, lambda: self._queue_access(temps)), instance)
        in_body = set(body)
        other_entries = {i: t for i, t in file_entries.items() if i != entry.index and i in in_body}
        info = RoutineInfo(key, entry, file, body, is_main, call_name, other_entries,
                           self.liveness.exit(key), lambda i: self.liveness.at(key, i), interface_call,
                           self._file_jumps(key[0]))
        self.current_key = key
        structured = True
        try:
            Structurer(info, executor()).region(body[0] if body else 0, (body[-1] + 1) if body else 0)
        except NotStructured as exc:
            structured = False
            self.fallbacks.append(Fallback(pou_name, exc.reason, file.ops[exc.index].span))
            emitter = Emitter(scratch)
            temps.clear()
            accessors.count.clear()
            callees.clear()
            slots.clear()
            ctx.out = emitter
            state_machine(info, executor())
        except Unsupported as exc:
            where = exc.span or (file.ops[body[0]].span if body else Span(file.path, 1))
            self.untranslated.append((where, f"{exc} (the whole of {pou_name} is left out)"))
            self.diags.report("E-UNSUPPORTED", where, f"{pou_name}: not translated: {exc}; the whole routine is "
                              "left out of the ST")
            emitter = Emitter()
            emitter.add(S.Comment(f"NOT TRANSLATED: {exc}"))
            la = self._register("LA")
            emitter.add(S.Assign(la, E.var(la, "BOOL")))
        emitter.flush_comments()
        self.calls[key] = callees
        statements = emitter.block
        if not S.has_code(statements):
            statements = statements + [S.Return("the subprogram does nothing")]
        local = [IecVar(self.instance_names[c], self.pou_names[c]) for c in sorted(callees)]
        local += [IecVar(inst, self.layout.bit_access[kind], comment=f"indexed access to {kind} operands")
                  for kind, inst in accessors.instances()]
        local += [IecVar(name, SLOT_TYPES[kind], comment=f"data stack entry {depth} of this routine")
                  for (depth, kind), name in sorted(slots.items())]
        local += [IecVar(n, t) for n, t in temps]
        if not structured:
            local.append(IecVar("HH_STATE", "DINT", comment="state of the irreducible control flow"))
        if not local and (iface is None or iface.empty) and _at_most_one_line_of_code(statements):
            # matiec rejects a FUNCTION_BLOCK or PROGRAM without any declaration.
            local.append(IecVar("HH_UNUSED", "BOOL", comment="placeholder: the subprogram has no data of its own"))
        sections = []
        if iface is not None and not iface.empty:
            params, results = self._names_of_interface(key)
            if params:
                sections.append(VarSection("VAR_INPUT", tuple(
                    IecVar(n, SLOT_TYPES[k], comment="pushed by the caller (PS)") for n, (_, k) in zip(params, iface.params))))
            if results:
                sections.append(VarSection("VAR_OUTPUT", tuple(
                    IecVar(n, SLOT_TYPES[k], comment="pulled by the caller (PL)") for n, (_, k) in zip(results, iface.results))))
        if local:
            sections.append(VarSection("VAR", tuple(local)))
        first = file.ops[body[0]].span.line if body else 1
        last = file.ops[body[-1]].span.line if body else 1
        label = "main program" if is_main else f"LBL {entry.label}"
        comment = f"{label} of {file.path}" + ("" if structured else " (irreducible jumps: state machine)")
        comments = list(file.ops[entry.index].comments) if body and not is_main else []
        if comments:
            comment += "\n" + "\n".join(comments)
        pou = Pou(pou_name, "PROGRAM" if is_main else "FUNCTION_BLOCK", tuple(sections), "",
                  comment=comment, source_map=(SourceRange(file.path, first, last),))
        # The error markers of x, / and MOD and of module calls (M4200-M4203 on the iTNC) are written by every such
        # instruction, so a store the next one overwrites before anything reads it is as dead as a register store.
        itf = self.semantics.profile.interface
        markers = (self.names.get(f"M{m}") for m in (itf.mul_err, itf.div_err, itf.mod_err, itf.module_err))
        overwritten = frozenset(n for r in REG_TYPES if (n := self.names.get(f"reg:{r}")) is not None)
        overwritten |= frozenset(n for n in markers if n is not None)
        statements = simplify.simplify(statements, overwritten)
        pou = printer.with_statements(pou, statements)
        if not any(name.startswith(TEMP_PREFIX) for name, _ in temps):
            return pou      # (no temporary to propagate: every name temp() gives starts so)
        return passes.propagate_temporaries(pou)

    def _file_jumps(self, index: int) -> list[int]:
        """The indices of the jumps with a target in file `index`, in order (worked out once per file: every
        routine of the file structures its own)."""
        jumps = self.file_jumps.get(index)
        if jumps is None:
            jumps = self.file_jumps[index] = [i for i, op in enumerate(self.program.files[index].ops)
                                              if op.code in JUMPS and op.target is not None]
        return jumps

    def _bit_accessor_pou(self, kind: str) -> Pou:
        """Indexed access to a bit space: a CASE over the named operands, the rest in one array (base + X)."""
        layout = self.layout
        arr = layout.bit_arrays[kind]
        named = [(addr, layout.ref(name)) for addr, name in layout.named_bits(kind)]
        index, value = E.var("IDX", "DINT"), E.var("VALUE", "BOOL")
        element = f"{layout.ref(arr)}[IDX]"
        if named:
            write: S.Stmt = S.Case(index, tuple(S.CaseBranch((addr,), (S.Assign(name, value),)) for addr, name in named),
                                   (S.Assign(element, value),))
            read: S.Stmt = S.Case(index, tuple(S.CaseBranch((addr,), (S.Assign("Q", E.var(name, "BOOL")),))
                                               for addr, name in named),
                                  (S.Assign("Q", E.Expr(element, "BOOL", frozenset([arr.upper(), "IDX"]), var=element)),))
        else:
            write = S.Assign(element, value)
            read = S.Assign("Q", E.Expr(element, "BOOL", frozenset([arr.upper(), "IDX"]), var=element))
        return printer.with_statements(Pou(layout.bit_access[kind], "FUNCTION_BLOCK", (
            VarSection("VAR_INPUT", (IecVar("IDX", "DINT", comment=f"{kind} operand address (base + X)"),
                                     IecVar("WRITE", "BOOL"), IecVar("VALUE", "BOOL"))),
            VarSection("VAR_OUTPUT", (IecVar("Q", "BOOL", comment="value of the operand (after a write: the new one)"),)),
        ), "", comment=f"indexed access to the {kind} operands: named operands keep their variables"),
            [S.If(E.var("WRITE", "BOOL"), (write,)), read])

    def _presets(self, layout: Layout) -> dict[str, int]:
        """Preset variables (in cycles) of the timers and counters the program uses; the MP file gives the defaults."""
        presets: dict[str, int] = {}
        self.preset_vars: dict[tuple[int, int], str] = {}
        timers, counters = load_presets(self.mp, self.semantics, int(self.semantics["cycle_time_ms"]), self.diags)
        for number, used, values, what in ((TIMER_MP, layout.timers, timers, "timer T"),
                                           (COUNTER_MP, layout.counters, counters, "counter C")):
            for n in used:
                cycles = values.get(n, 0)
                name = self.layout.add_register(f"mp:{number}.{n}", f"MP{number}_{n}", "DINT",
                                                f"{what}{n} preset in cycles (MP{number}.{n} = "
                                                f"{self.mp.get((number, n), Decimal(0))})", str(cycles), group="mp")
                presets[name] = cycles
                self.preset_vars[(number, n)] = name
        return presets

    def _data_load(self, layout: Layout) -> list[S.Stmt]:
        """The PLC data tables as a list of retained globals with the tables' values as initial values (what a
        commissioning engineer edits on the target), and the statement that loads them into their operands before
        the program of the first cycle and of every cycle that sees the MP-restart marker (M4174), as the
        reference interpreter does (Machine.data_phase)."""
        rows = self.program.data_rows
        self.data_vars: dict[str, tuple[str, str, DataRow]] = {}
        if not rows:
            return []
        loaded = layout.add_register("data:loaded", "HH_data_loaded", "BOOL",
                                     "the data tables were loaded since the PLC started")
        condition = E.Expr(f"NOT {layout.ref(loaded)}", "BOOL", frozenset([loaded.upper()]))
        restart = self.semantics.profile.interface.mp_restart
        if restart is not None:
            marker = layout.bit_lvalue(Operand("M", restart))
            condition = E.Expr(f"{condition.text} OR {marker.text}", "BOOL", condition.deps | marker.deps)
        body: list[S.Stmt] = []
        for row in rows:
            typ = {"M": "BOOL", "S": "STRING"}.get(row.kind) or MEM_TYPE[row.kind]
            initial = ("TRUE" if row.value else "FALSE") if row.kind == "M" else \
                "'" + str(row.value).replace("$", "$$").replace("'", "$'") + "'" if row.kind == "S" else str(row.value)
            name = self.names.name(f"data:{row.symbol}", f"{row.symbol}_table")
            layout.add_data(name, typ, initial, f"{row.key} row {row.nr if row.nr is not None else '-'} "
                            f"({row.table}:{row.span.line}) -> {row.operand_text}")
            self.data_vars[row.key] = (name, typ, row)
            value = E.var(layout.ref(name), typ)
            operand = Operand(row.kind, row.addr, symbol=row.symbol)
            if row.kind == "M":
                body.append(S.Assign(layout.bit_lvalue(operand).text, value))
            elif row.kind == "S":
                body.append(S.Assign(layout.string_lvalue(operand, None).text, value))
            else:
                body += [S.Assign(target, expr) for target, expr in layout.write_value(operand, None, value)]
        body.append(S.Assign(layout.ref(loaded), E.Expr("TRUE", "BOOL", frozenset())))
        return [S.Comment("PLC data tables: loaded at power-on and at an MP restart (M4174), see "
                          "docs/language.md#plc-data-tables"), S.If(condition, tuple(body))]

    def _with_services(self, main: Pou, layout: Layout, data_load: list[S.Stmt] = ()) -> Pou:
        prof = self.semantics.profile
        service: list[S.Stmt] = list(data_load)
        local = list(main.sections[0].vars) if main.sections else []
        if layout.timers or layout.counters:
            service.append(S.Comment("phase 3: timer and counter service, see docs/language.md#timers-and-counters"))
        for t in layout.timers:
            start = layout.timer_var("T", t)
            inst = self.names.name(f"timer:{t}", _service_name(start, "timer", f"Timer{t}"))
            local.append(IecVar(inst, "HH_TIMER", comment=f"service of T{t} / T{t - prof.timer_start[0] + prof.timer_running[0]}"))
            running = layout.timer_var("T", t - prof.timer_start[0] + prof.timer_running[0])
            preset = E.var(layout.ref(self.preset_vars[(TIMER_MP, t)]), "DINT")
            service.append(S.Call(inst, (("START", start), ("PRESET", preset))))
            service.append(S.Assign(running.text, E.var(f"{inst}.RUNNING", "BOOL")))
        for c in layout.counters:
            start = layout.timer_var("C", prof.counter_start[0] + c)
            inst = self.names.name(f"counter:{c}", _service_name(start, "counter", f"Counter{c}"))
            local.append(IecVar(inst, "HH_COUNTER", comment=f"service of C{c}"))
            running = layout.timer_var("C", prof.counter_running[0] + c)
            release = layout.timer_var("C", prof.counter_release[0] + c)
            preset = E.var(layout.ref(self.preset_vars[(COUNTER_MP, c)]), "DINT")
            service.append(S.Call(inst, (("START", start), ("PRESET", preset), ("RELEASE", release))))
            service.append(S.Assign(running.text, E.var(f"{inst}.RUNNING", "BOOL")))
        if self.stack is not None:
            service.append(S.Assign(self.stack[1], E.int_const(0, "INT"),
                                    "the data stack is empty at the start of each cycle (A-19)"))
        if service:
            service.append(S.Comment("phase 4: main program"))
        sections = (VarSection("VAR", tuple(local)),) + main.sections[1:] if local else main.sections
        return printer.with_statements(dataclasses.replace(main, sections=sections), service + list(main.statements))

    def _order(self, pous: dict[tuple[int, int], Pou]) -> list[Pou]:
        """Callees before callers (matiec needs declarations before use)."""
        order: list[tuple[int, int]] = []
        seen: set[tuple[int, int]] = set()

        def visit(key: tuple[int, int]) -> None:
            stack = [(key, iter(sorted(self.calls.get(key, ()))))]
            seen.add(key)
            while stack:
                node, it = stack[-1]
                nxt = next((c for c in it if c not in seen), None)
                if nxt is None:
                    stack.pop()
                    if node in pous:
                        order.append(node)
                    continue
                seen.add(nxt)
                stack.append((nxt, iter(sorted(self.calls.get(nxt, ())))))

        for key in sorted(pous):
            if key not in seen:
                visit(key)
        return [pous[k] for k in order]

    def _types(self, layout: Layout) -> list[DataType]:
        out = []
        for name, (elem, lo, hi) in sorted(layout.types.items()):
            out.append(DataType(name, "array", elem, (ArrayDim(lo, hi),)))
        for group in layout.marker_groups:
            fields = layout.struct_fields.get(group.type_name)
            if fields:
                out.append(DataType(group.type_name, "struct", fields=tuple(
                    IecVar(member, "BOOL", comment=comment) for member, comment in fields),
                    comment=f"the markers {group.name}_*: one member per symbol"))
        return out + self.types

    def _job_queue(self) -> str:
        """The global submit-job queue, as the POU bodies name it (declared on first use)."""
        if self.job_queue is None:
            self.job_queue = self.layout.ref(self.layout.add_register("jobs", jobs.QUEUE_DATA, jobs.QUEUE_TYPE,
                                                                      "queued and running submit jobs", group="jobs"))
        return self.job_queue

    def _queue_access(self, temps: list[tuple[str, str]] | None = None) -> jobs.QueueAccess:
        """The queue as one POU reaches it: the block's instance (added to `temps`, the POU's locals, on first use;
        one name in every POU) and the global queue."""
        instance = self.names.name("jobs:block", jobs.QUEUE_INSTANCE)
        if temps is not None and (instance, jobs.QUEUE_FB) not in temps:
            temps.append((instance, jobs.QUEUE_FB))
        return jobs.QueueAccess(instance, self._job_queue())

    def _jobs_program(self, layout: Layout) -> Pou:
        """The PROGRAM that runs the queued jobs after the main program, each with its own registers and error
        markers (see jobs.py); built after every routine, so it saves exactly the variables that exist."""
        own: list[jobs.OwnValue] = []
        for reg, clear in (("LA", "FALSE"), ("WA", "0"), ("X", "0"), ("SA", "''")):
            name = self.names.get(f"reg:{reg}")
            if name is not None and name in layout.globals:
                own.append(jobs.OwnValue(layout.ref(name), clear, REG_TYPES[reg][0]))
        itf = self.semantics.profile.interface
        for addr in (itf.mul_err, itf.div_err, itf.mod_err, itf.module_err):
            if addr is not None and ("M", addr) in layout._bit_var:
                own.append(jobs.OwnValue(layout.ref(layout._bit_var[("M", addr)]), "FALSE", "BOOL"))
        word = itf.module_err_code_word
        if word is not None and (("W", word) in layout._mem_var or layout.mem_array is not None):
            for lhs, zero in layout.write_value(Operand("W", word), None, E.int_const(0)):
                own.append(jobs.OwnValue(lhs, zero.text, "BYTE" if "[" in lhs else "INT"))
        in_job = self.names.get("in_job")
        in_job = layout.ref(in_job) if in_job is not None else None
        name = self.names.name(f"{POU_KEY_PREFIX}jobs", "HH_SubmitJobs")
        calls = [jobs.JobCall(number, self.instance_names[key], self.pou_names[key],
                              f"{self.job_plan.labels[key]} of {self.program.files[key[0]].path}")
                 for key, number in self.job_plan.numbers.items()]
        return jobs.jobs_program(name, self._queue_access(), self.semantics["submit_model"], calls,
                                 own, self.stack[1] if self.stack is not None else None, in_job,
                                 lambda wanted: self.names.name(f"jobs:{wanted}", wanted))

    def _configuration(self, layout: Layout, job_program: Pou | None) -> Configuration:
        groups: dict[str, list[IecVar]] = {}
        for g in layout.globals.values():
            groups.setdefault(g.group, []).append(IecVar(g.name, g.type, g.initial, g.address, g.comment))
        sections = []
        for key, title in GROUP_TITLES.items():
            if key in groups:
                # The data tables are kept over a power cycle (VAR_GLOBAL RETAIN, which every target hh2iec writes
                # for has) like the table files on the control.
                sections.append(VarSection("VAR_GLOBAL", tuple(groups[key]), comment=title, retain=key == "data"))
        for key in groups:
            if key not in GROUP_TITLES:
                sections.append(VarSection("VAR_GLOBAL", tuple(groups[key]), comment=group_title(key)))
        cycle = int(self.semantics["cycle_time_ms"])
        task = self.names.name("task", "HH_Cycle")
        inst = self.names.name("instance", f"PLC_{self.main_pou}")
        programs = [ProgramInstance(inst, task, self.main_pou)]
        if job_program is not None:
            # In the same task after the main program: the jobs run in phase 5 of the cycle.
            programs.append(ProgramInstance(self.names.name("instance:jobs", f"PLC_{job_program.name}"), task,
                                            job_program.name))
        # Config0/Res0: the names OpenPLC's runtime build expects (and OpenPLC Editor and Beremiz give a new project).
        return Configuration(self.names.name("config", "Config0"), self.names.name("resource", "Res0"),
                             (Task(task, cycle, 0),), tuple(programs), tuple(sections))


def _at_most_one_line_of_code(statements: list[S.Stmt]) -> bool:
    """Every statement but the last is a comment (one that names no RETURN), and the last prints as one line."""
    *before, last = statements
    for s in before:        # (most bodies: a comment or two, then code)
        if type(s) is not S.Comment or "RETURN" in s.text + (s.note or ""):
            return False
    return printer.one_line(last)


def _service_name(start: E.Expr, what: str, fallback: str) -> str:
    """The service FB instance of a timer or counter, named after its start operand (`TS_unclamp_Z_timer`); an
    operand held in an array element (reached through the index register) gives `Timer8`."""
    name = E.unqualified(start.text)
    return f"{name}_{what}" if start.var is not None and name.isidentifier() else fallback


def _module_effect(number: int) -> Effect | None:
    """What a CM of a PLC module does to the data stack, for the stack analysis (modcalls.py)."""
    effect = modcalls.stack_effect(number)
    return Effect(*effect) if effect is not None else None


def _names_used(pou: Pou) -> set[str]:
    """Every name the POU's statements hold (upper case), from its statement tree: the lvalue, callee and input
    names of its statements and the names its expressions were built from. A POU written as text alone is read
    from its text (names in comments do not count)."""
    if not pou.statements:
        return {m.group(0).upper() for m in _IDENT.finditer(_COMMENT.sub("", pou.body))}
    found: set[str] = set()
    targets: set[str] = set()       # lvalue, callee and input texts, each looked at once
    _statement_names(pou.statements, found, targets)
    for text in targets:
        if text.isidentifier() and text.isascii():      # (most: a plain variable, its own name)
            found.add(text.upper())
        else:
            found |= E.text_names(text)
    return found


def _statement_names(block, found: set[str], targets: set[str]) -> None:
    """The names of `block`'s expressions into `found`, its lvalue, callee and input texts into `targets` (nested
    blocks included; a plain recursion: a POU's statements are thousands of trees of a few levels)."""
    names_of = E.names_of
    for s in block:
        kind = type(s)
        if kind is S.Assign:
            targets.add(s.target)
            found |= names_of(s.value)
        elif kind is S.Call:
            targets.add(s.callee)
            for name, value in s.args:
                targets.add(name)
                found |= names_of(value)
        elif kind is S.If:
            found |= names_of(s.cond)
            _statement_names(s.then, found, targets)
            _statement_names(s.orelse, found, targets)
        elif kind is S.Case:
            found |= names_of(s.selector)
            for inner in S.blocks(s):
                _statement_names(inner, found, targets)
        elif kind is S.While:
            found |= names_of(s.cond)
            _statement_names(s.body, found, targets)
        elif kind is S.Repeat:
            found |= names_of(s.until)
            _statement_names(s.body, found, targets)


def _with_externals(pou: Pou, globals_by_upper: Mapping[str, tuple[IecVar, str | None]],
                    area_order: Mapping[str | None, int], declarations: dict[str, IecVar]) -> Pou:
    """`pou` with a VAR_EXTERNAL declaration of every global its body names (names in comments do not count),
    one block per area of the configuration's globals (`area_order`: their order), titled like it: matiec needs
    these declarations (a POU sees no global without one), the blocks make the long lists readable.
    `declarations` keeps the declaration of each global made so far, for the next POU that names it."""
    used = _names_used(pou)
    local = {v.name.upper() for s in pou.sections for v in s.vars}
    by_area: dict[str | None, list[IecVar]] = {}
    for u in sorted(globals_by_upper.keys() & (used - local)):    # (the same order; fewer names to sort)
        var, area = globals_by_upper[u]
        declaration = declarations.get(u)
        if declaration is None:
            declaration = declarations[u] = IecVar(var.name, var.type)
        by_area.setdefault(area, []).append(declaration)
    if not by_area:
        return pou
    externals = tuple(VarSection("VAR_EXTERNAL", tuple(vars_), comment=area)
                      for area, vars_ in sorted(by_area.items(), key=lambda item: area_order[item[0]]))
    return replaced(pou, sections=pou.sections + externals)
