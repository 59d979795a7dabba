"""Resolves the declarations of an ST file (types, POUs, globals, configuration) and compiles it to one Python module."""

from __future__ import annotations

import functools
import math
from typing import Optional

from transpiler.diagnostics import Diagnostics, Span
from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.codegen import (Context, Ex, PouCompiler, default_code, location_attr, normalise_address,
                                       storage_attr)
from transpiler.exec.stexec.errors import ST_CODE, StError
from transpiler.exec.stexec.keywords import is_reserved_word
from transpiler.exec.stexec.model import CompiledProject, PouInfo, ProgramInstance, TaskInfo, VarInfo
from transpiler.exec.stexec.parser import parse
from transpiler.exec.stexec.prelude import prelude_text
from transpiler.exec.stexec.stdlib import is_standard_name

PRELUDE_FILE = "<iec-standard-library>"
# The type an address's size prefix implies: its width must match a declaration, and it types an undeclared use.
_SIZE_TYPE = {"X": T.BOOL, "B": T.BYTE, "W": T.WORD, "D": T.DWORD, "L": T.LWORD}
_KIND_NAMES = {"input": "VAR_INPUT", "output": "VAR_OUTPUT", "inout": "VAR_IN_OUT", "var": "VAR",
               "temp": "VAR_TEMP", "external": "VAR_EXTERNAL", "global": "VAR_GLOBAL"}
_ALLOWED_KINDS = {
    "function": {"input", "output", "inout", "var", "temp"},
    "function_block": {"input", "output", "inout", "var", "temp", "external"},
    "program": {"input", "output", "inout", "var", "temp", "external"},
}


@functools.lru_cache(maxsize=1)
def _prelude() -> n.SourceFile:
    return parse(prelude_text(), PRELUDE_FILE)


class _Source:
    """Accumulates generated Python lines together with the ST span each one came from."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.spans: list[Optional[Span]] = []

    def add(self, indent: int, text: str, span: Optional[Span] = None) -> None:
        self.lines.append("    " * indent + text)
        self.spans.append(span)


class Compiler:
    def __init__(self, filename: str, loop_limit: int):
        self.filename = filename
        self.diags = Diagnostics()
        self.ctx = Context(self.error, loop_limit)
        self.locations: dict[str, tuple[T.Type, str, Span]] = {}
        self.programs: list[ProgramInstance] = []
        self.tasks: list[TaskInfo] = []
        self.has_configuration = False
        self.structs: list[T.StructT] = []
        self.prelude_keys: set[str] = set()
        self.ctx.use_address = self.use_address

    def use_address(self, addr: str, span: Span) -> Optional[tuple[T.Type, str]]:
        """Storage of an address used directly in code: the declared type, else the size prefix's bit string."""
        prev = self.locations.get(addr)
        if prev is not None:
            return prev[0], prev[1]
        ty = _SIZE_TYPE[addr[2]]
        attr = location_attr(addr)
        self.locations[addr] = (ty, attr, span)
        return ty, attr

    def error(self, span: Optional[Span], message: str) -> None:
        self.diags.report(ST_CODE, span or Span(self.filename, 1, 1), message)

    # ================================================================ driver
    def run(self, text: str) -> CompiledProject:
        user = parse(text, self.filename)
        elements = [(el, True) for el in _prelude().elements] + [(el, False) for el in user.elements]
        pous: list[PouInfo] = []
        configs: list[tuple[n.Configuration, int]] = []
        for ordinal, (el, is_prelude) in enumerate(elements):
            if isinstance(el, n.TypeBlock):
                for decl in el.decls:
                    self.declare_type(decl, ordinal)
            elif isinstance(el, n.Pou):
                info = self.declare_pou(el, ordinal, is_prelude)
                if info is not None:
                    pous.append(info)
            elif isinstance(el, n.GlobalBlock):
                self.declare_globals(el.block, ordinal)
            elif isinstance(el, n.Configuration):
                configs.append((el, ordinal))
        for cfg, ordinal in configs[:1]:
            self.declare_configuration(cfg, ordinal)
        for cfg, _ in configs[1:]:
            self.error(cfg.span, "only one CONFIGURATION per file is supported")
        for info in pous:
            self.resolve_externals(info)
        src = _Source()
        self.emit_structs(src)
        for info in pous:
            self.emit_pou(src, info)
        self.emit_globals(src)
        if self.diags.has_errors():
            raise StError(self.diags.errors)
        source = "\n".join(src.lines) + "\n"
        try:
            code = compile(source, f"<stexec:{self.filename}>", "exec")
        except (SyntaxError, RecursionError, MemoryError) as exc:
            span = None
            lineno = getattr(exc, "lineno", None)
            if lineno and 0 < lineno <= len(src.spans):
                span = src.spans[lineno - 1]
            self.error(span, f"statement too complex for the built-in executor ({type(exc).__name__}: {exc})")
            raise StError(self.diags.errors) from None
        return CompiledProject(
            filename=self.filename, code=code, source=source, line_spans=[None] + src.spans,
            pous=self.ctx.pous, globals=self.ctx.globals,
            locations={a: (t, attr) for a, (t, attr, _s) in self.locations.items()},
            programs=self.programs, tasks=self.tasks, has_configuration=self.has_configuration,
            loop_limit=self.ctx.loop_limit)

    # ================================================================ names
    def check_name(self, name: str, span: Span, prelude: bool, what: str) -> bool:
        key = name.lower()
        if prelude:
            return True
        if "__" in key or key.endswith("_"):
            self.error(span, f"invalid {what} name '{name}': IEC identifiers have no double or trailing underscore")
            return False
        if is_reserved_word(key):
            self.error(span, f"'{name}' is a reserved word of IEC 61131-3 and cannot be a {what} name")
            return False
        if is_standard_name(key) or key in self.prelude_keys or key in ("en", "eno"):
            self.error(span, f"'{name}' is the name of a standard function or function block and cannot be a "
                             f"{what} name")
            return False
        return True

    # ================================================================ types
    def resolve_spec(self, spec: n.TypeSpec, ordinal: int, owner: str = "") -> tuple[T.Type, Optional[n.Init]]:
        if isinstance(spec, n.NamedTypeSpec):
            key = spec.name.lower()
            if key in T.ELEMENTARY:
                return T.ELEMENTARY[key], None
            if key in T.UNSUPPORTED_ELEMENTARY:
                self.error(spec.span, f"type {spec.name.upper()} is not supported by the built-in executor")
                return T.ERR, None
            entry = self.ctx.types.get(key)
            if entry is not None:
                if entry[2] >= ordinal:
                    self.error(spec.span, f"type '{spec.name}' is used before its declaration")
                    return T.ERR, None
                return entry[0], entry[1]
            pou = self.ctx.pous.get(key)
            if pou is not None and pou.kind == "function_block":
                if pou.ordinal >= ordinal:
                    self.error(spec.span, f"function block '{spec.name}' is used before its declaration")
                    return T.ERR, None
                return pou.fbtype, None
            if pou is not None:
                self.error(spec.span, f"'{spec.name}' is a {pou.kind.replace('_', ' ')}, not a type")
                return T.ERR, None
            self.error(spec.span, f"unknown type '{spec.name}'")
            return T.ERR, None
        if isinstance(spec, n.StringSpec):
            self.error(spec.span, "STRING[n] is rejected by matiec (it parses, then every use fails); use STRING")
            return T.ERR, None
        if isinstance(spec, n.SubrangeSpec):
            b = T.ELEMENTARY.get(spec.base.lower())
            if b is None or b.cat != "int":
                self.error(spec.span, f"a subrange needs an integer base type, not {spec.base}")
                return T.ERR, None
            if not (b.lo <= spec.lo <= spec.hi <= b.hi):
                self.error(spec.span, f"invalid subrange {spec.lo}..{spec.hi} of {b}")
                return T.ERR, None
            return T.SubrangeT(b, spec.lo, spec.hi), None
        if isinstance(spec, n.ArraySpec):
            for lo, hi in spec.ranges:
                if lo > hi:
                    self.error(spec.span, f"empty array range {lo}..{hi}")
                    return T.ERR, None
            elem, _ = self.resolve_spec(spec.elem, ordinal)
            if isinstance(elem, T.ArrayT):
                self.error(spec.span, "ARRAY OF ARRAY is not supported by matiec; use ARRAY[a..b, c..d]")
                return T.ERR, None
            if isinstance(elem, T.FbT):
                self.error(spec.span, "arrays of function block instances are rejected by matiec")
                return T.ERR, None
            if elem is T.ERR:
                return T.ERR, None
            dims = ", ".join(f"{lo}..{hi}" for lo, hi in spec.ranges)
            return T.ArrayT(owner or f"ARRAY[{dims}] OF {elem}", list(spec.ranges), elem), None
        raise AssertionError(spec)

    def declare_type(self, decl: n.TypeDecl, ordinal: int) -> None:
        key = decl.name.lower()
        if not self.check_name(decl.name, decl.span, False, "type"):
            return
        if key in self.ctx.types or key in self.ctx.pous or key in T.ELEMENTARY:
            self.error(decl.span, f"'{decl.name}' is declared twice")
            return
        spec = decl.spec
        init = decl.init
        if isinstance(spec, n.StructSpec):
            fields: dict[str, T.StructField] = {}
            for el in spec.elems:
                fty, finit = self.resolve_spec(el.spec, ordinal + 1)
                if isinstance(fty, T.FbT):
                    self.error(el.span, "function block instances inside a STRUCT are rejected by matiec")
                    fty = T.ERR
                if el.name.lower() in fields:
                    self.error(el.span, f"field '{el.name}' is declared twice")
                    continue
                fields[el.name.lower()] = T.StructField(el.name, fty, el.init if el.init is not None else finit)
            ty: T.Type = T.StructT(decl.name, fields, "S_" + key)
            self.structs.append(ty)
        elif isinstance(spec, n.EnumSpec):
            values = [v for v, _s in spec.values]
            seen = set()
            for v, vspan in spec.values:
                if v.lower() in seen:
                    self.error(vspan, f"enum value '{v}' is declared twice")
                seen.add(v.lower())
            ety = T.EnumT(decl.name, values)
            if spec.default is not None:
                idx = ety.index(spec.default)
                if idx is None:
                    self.error(spec.span, f"'{spec.default}' is not a value of {decl.name}")
                else:
                    ety.default = idx
            for i, v in enumerate(values):
                self.ctx.enum_values.setdefault(v.lower(), []).append((ety, i))
            ty = ety
        else:
            ty, named_init = self.resolve_spec(spec, ordinal + 1, owner=decl.name)
            if isinstance(ty, T.SubrangeT) and isinstance(spec, n.SubrangeSpec):
                ty.name = decl.name
            if init is None:
                init = named_init
            if isinstance(ty, T.FbT):
                self.error(decl.span, "a TYPE cannot name a function block")
                ty = T.ERR
        self.ctx.types[key] = (ty, init, ordinal)

    # ================================================================ variables
    def declare_vars(self, block: n.VarBlock, ordinal: int, owner: Optional[PouInfo], prelude: bool) -> list[VarInfo]:
        out: list[VarInfo] = []
        located = [d.location is not None for d in block.decls]
        if any(located) and not all(located):
            self.error(block.span, "located and non-located variables in one VAR block are rejected by matiec; "
                                   "put located variables in their own block")
        for decl in block.decls:
            ty, named_init = self.resolve_spec(decl.spec, ordinal)
            init = decl.init if decl.init is not None else named_init
            location = None
            if decl.location is not None:
                location = self.check_location(decl, ty, block, owner)
            names = decl.names or [(f"AT {decl.location}", decl.span)]
            for name, span in names:
                if decl.names and not self.check_name(name, span, prelude, "variable"):
                    continue
                if decl.names and not prelude and (name.lower() in self.ctx.pous or name.lower() in self.ctx.types):
                    self.error(span, f"'{name}' is the name of a POU or type and cannot name a variable")
                    continue
                v = VarInfo(name, ty, block.kind, span, block.constant, block.retain, init, location)
                if block.constant and init is None and block.kind != "external":
                    self.error(span, f"CONSTANT '{name}' needs an initial value")
                if isinstance(ty, T.FbT) and owner is not None and owner.kind == "function":
                    self.error(span, "function block instances cannot be declared inside a FUNCTION")
                out.append(v)
                if location is not None:
                    self.register_location(v, decl)
        return out

    def check_location(self, decl: n.VarDecl, ty: T.Type, block: n.VarBlock, owner: Optional[PouInfo]) -> Optional[str]:
        addr = normalise_address(decl.location)
        if addr is None:
            self.error(decl.span, f"unsupported address '{decl.location}' (the built-in executor needs a full "
                                  "address such as %QX0.1)")
            return None
        if owner is not None and owner.kind != "program":
            self.error(decl.span, f"located variables inside a {owner.kind.replace('_', ' ').upper()} are "
                                  "rejected by matiec (a FUNCTION_BLOCK even crashes iec2c)")
            return None
        if block.kind not in ("var", "global"):
            self.error(decl.span, f"located variables are only allowed in VAR or VAR_GLOBAL, not "
                                  f"{_KIND_NAMES[block.kind]}")
            return None
        b = T.base(ty)
        size = _SIZE_TYPE[addr[2]].bits
        if isinstance(b, T.ArrayT):
            if decl.spec.__class__ is n.ArraySpec:
                self.error(decl.span, "an inline ARRAY cannot be located (matiec: bit size error); use a named "
                                      "array TYPE")
                return None
        elif not isinstance(b, T.Elem) or b.cat in ("string", "time") or b.bits != size:
            self.error(decl.span, f"bit size of data type {ty} is incompatible with bit size of location {addr}")
            return None
        return addr

    def register_location(self, v: VarInfo, decl: n.VarDecl) -> None:
        attr = storage_attr(v)
        prev = self.locations.get(v.location)
        if prev is not None:
            if not T.same(prev[0], v.ty):
                self.error(v.span, f"address {v.location} is declared with type {v.ty} here but {prev[0]} at line "
                                   f"{prev[2].line}")
            return
        self.locations[v.location] = (v.ty, attr, v.span)

    def constant_values(self, vars_: list[VarInfo], ordinal: int) -> None:
        pc = PouCompiler(self.ctx, None, ordinal)
        for v in vars_:
            if v.constant and v.init is not None and isinstance(T.base(v.ty), (T.Elem, T.EnumT)) \
                    and not isinstance(v.init, (n.ArrayInit, n.StructInit)):
                ex = pc.expr(v.init)
                if ex.ty is T.ERR:
                    continue
                ex = pc.coerce(ex, v.ty, v.init.span, "initial value")
                if ex.ty is not T.ERR and ex.const is not None:
                    v.const_value = ex.const
                elif ex.ty is not T.ERR:
                    self.error(v.init.span, "an initial value must be a literal (constant expression)")

    # ================================================================ POUs
    def declare_pou(self, node: n.Pou, ordinal: int, prelude: bool) -> Optional[PouInfo]:
        key = node.name.lower()
        if not self.check_name(node.name, node.span, prelude, node.kind.replace("_", " ")):
            return None
        if key in self.ctx.pous or key in self.ctx.types:
            self.error(node.span, f"'{node.name}' is declared twice")
            return None
        info = PouInfo(node.kind, node.name, node, ordinal, prelude)
        if prelude:
            self.prelude_keys.add(key)
        if node.kind == "function_block":
            info.fbtype = T.FbT(node.name, info)
        self.ctx.pous[key] = info
        if node.kind == "function":
            rty, _ = self.resolve_spec(node.result, ordinal)
            if isinstance(rty, T.FbT):
                self.error(node.result.span, "a FUNCTION cannot return a function block")
                rty = T.ERR
            info.result = rty
            info.vars[key] = VarInfo(node.name, rty, "result", node.span)
        has_input = False
        for block in node.blocks:
            if block.kind not in _ALLOWED_KINDS[node.kind]:
                if block.kind == "external" and node.kind == "function":
                    self.error(block.span, "unexpected external variable(s) declaration in function declaration "
                                           "(functions cannot see globals; use a FUNCTION_BLOCK with VAR_EXTERNAL)")
                else:
                    self.error(block.span, f"{_KIND_NAMES[block.kind]} is not allowed in a "
                                           f"{node.kind.replace('_', ' ').upper()}")
                continue
            for v in self.declare_vars(block, ordinal, info, prelude):
                if v.key in info.vars:
                    self.error(v.span, f"'{v.name}' is declared twice in {node.name}")
                    continue
                info.vars[v.key] = v
                has_input = has_input or v.kind in ("input", "inout")
        if node.kind == "function" and not has_input:
            self.error(node.span, f"FUNCTION {node.name} has no input; matiec rejects calls without parameters")
        self.constant_values(list(info.vars.values()), ordinal)
        return info

    def declare_globals(self, block: n.VarBlock, ordinal: int) -> None:
        vars_ = self.declare_vars(block, ordinal, None, False)
        for v in vars_:
            if v.key in self.ctx.globals:
                self.error(v.span, f"global '{v.name}' is declared twice")
                continue
            self.ctx.globals[v.key] = v
        self.constant_values(vars_, ordinal)

    def resolve_externals(self, info: PouInfo) -> None:
        for v in info.vars.values():
            if v.kind != "external":
                continue
            g = self.ctx.globals.get(v.key)
            if g is None:
                self.error(v.span, f"the external variable '{v.name}' does not match any global variable")
                continue
            if not T.same(g.ty, v.ty) and v.ty is not T.ERR and g.ty is not T.ERR:
                self.error(v.span, f"data type mismatch between external ({v.ty}) and global ({g.ty}) declarations "
                                   "of '{0}' (arrays need one named TYPE)".format(v.name))
            if g.constant and not v.constant:
                self.error(v.span, f"the external variable '{v.name}' must be declared CONSTANT, as it maps to a "
                                   "constant global variable")
            v.const_value = g.const_value if g.constant else None
            v.location = g.location

    # ================================================================ configuration
    def declare_configuration(self, cfg: n.Configuration, ordinal: int) -> None:
        self.has_configuration = True
        for block in cfg.globals:
            self.declare_globals(block, ordinal)
        if len(cfg.resources) > 1:
            self.error(cfg.resources[1].span, "use exactly one RESOURCE (matiec defines the POUs once per "
                                              "resource and the link fails)")
        for res in cfg.resources[:1]:
            for block in res.globals:
                self.declare_globals(block, ordinal)
            tasks: dict[str, TaskInfo] = {}
            for task in res.tasks:
                info = self.declare_task(task, ordinal)
                if info is not None:
                    if info.name.lower() in tasks:
                        self.error(task.span, f"task '{task.name}' is declared twice")
                    tasks[info.name.lower()] = info
                    self.tasks.append(info)
            if not tasks:
                self.error(res.span, "the resource needs at least one periodic TASK (matiec: you must define at "
                                     "least one periodic task)")
            names = set()
            for pc in res.programs:
                self.declare_program_instance(pc, tasks, names, ordinal)

    def declare_task(self, task: n.Task, ordinal: int) -> Optional[TaskInfo]:
        params = {name.lower(): (expr, span) for name, expr, span in task.params}
        unknown = set(params) - {"interval", "priority", "single"}
        if unknown:
            self.error(task.span, f"unknown TASK parameter {', '.join(sorted(unknown))}")
            return None
        if "single" in params:
            self.error(task.span, "TASK SINGLE is not supported by the built-in executor")
            return None
        if "priority" not in params:
            self.error(task.span, "no task initialization defined in task declaration (PRIORITY is required)")
            return None
        if "interval" not in params:
            self.error(task.span, "the built-in executor needs a periodic TASK with INTERVAL")
            return None
        pc = PouCompiler(self.ctx, None, ordinal)
        iv = pc.expr(params["interval"][0])
        pr = pc.expr(params["priority"][0])
        if iv.ty is T.ERR or pr.ty is T.ERR:
            return None
        if T.base(iv.ty) is not T.TIME or iv.const is None or iv.const <= 0:
            self.error(params["interval"][1], "TASK INTERVAL must be a positive TIME literal such as T#10ms")
            return None
        if not isinstance(pr.const, int) or isinstance(pr.const, bool):
            self.error(params["priority"][1], "TASK PRIORITY must be an integer literal")
            return None
        return TaskInfo(task.name, iv.const, pr.const, task.span)

    def declare_program_instance(self, pc: n.ProgramConf, tasks: dict[str, TaskInfo], names: set[str],
                                 ordinal: int) -> None:
        pou = self.ctx.pous.get(pc.type_name.lower())
        if pou is None or pou.kind != "program":
            self.error(pc.span, f"'{pc.type_name}' is not a PROGRAM declared before the configuration")
            return
        if pc.name.lower() == pou.key:
            self.error(pc.span, "invalid program name defined in program configuration (the instance name equals "
                                "the program type name)")
            return
        if pc.name.lower() in names or pc.name.lower() in self.ctx.globals:
            self.error(pc.span, f"'{pc.name}' is declared twice")
            return
        if pc.has_args:
            self.error(pc.span, "program parameters bound in the configuration make matiec generate C that does "
                                "not compile; share data through VAR_GLOBAL/VAR_EXTERNAL")
            return
        task = None
        if pc.task is not None:
            task = tasks.get(pc.task.lower())
            if task is None:
                self.error(pc.span, f"unknown task '{pc.task}'")
                return
        names.add(pc.name.lower())
        self.programs.append(ProgramInstance(pc.name, pou, task, pc.span))

    # ================================================================ code generation
    def emit_structs(self, src: _Source) -> None:
        for st in self.structs:
            pc = PouCompiler(self.ctx, None, self.ctx.types[st.name.lower()][2] + 1)
            _storage_class(src, st.pyname, [(f"v_{k}", pc.init_code(f.ty, f.init, st_span(f, self.filename)), None)
                                            for k, f in st.fields.items()])
            src.add(1, "def _copy(self):")
            src.add(2, f"o = {st.pyname}.__new__({st.pyname})")
            for k, f in st.fields.items():
                src.add(2, f"o.v_{k} = {PouCompiler.copy_code(f.ty, 'self.v_' + k)}")
            src.add(2, "return o")
            src.add(1, "def _set(self, o):")
            for k, f in st.fields.items():
                lines = pc.assign_lines(Ex(f"self.v_{k}", f.ty), Ex(f"o.v_{k}", f.ty))
                for line in lines:
                    src.add(2, line)
            src.add(2, "return self")

    def emit_pou(self, src: _Source, info: PouInfo) -> None:
        pc = PouCompiler(self.ctx, info, info.ordinal)
        header_span = info.node.span
        if info.kind == "function":
            params = ", ".join(f"v_{v.key}" for v in info.pyparams)
            src.add(0, f"def F_{info.key}({params}):", header_span)
            for v in info.vars.values():
                if v.kind in ("output", "var", "temp"):
                    if v.constant and v.const_value is not None:
                        continue
                    src.add(1, f"v_{v.key} = {pc.init_code(v.ty, v.init, v.span)}", v.span)
            src.add(1, f"v_{info.key} = {default_code(info.result) if info.result is not T.ERR else 'None'}",
                    header_span)
            pc.stmts(info.node.body)
            for indent, text, span in pc.lines:
                src.add(indent, text, span)
            src.add(1, pc.return_line(), info.node.end_span)
            return
        _storage_class(src, f"C_{info.key}", [(f"v_{v.key}", pc.init_code(v.ty, v.init, v.span), v.span)
                                              for v in info.state_vars], header_span)
        src.add(0, f"def B_{info.key}(self):", header_span)
        for v in info.vars.values():
            if v.kind == "temp":
                src.add(1, f"v_{v.key} = {pc.init_code(v.ty, v.init, v.span)}", v.span)
        pc.stmts(info.node.body)
        for indent, text, span in pc.lines:
            src.add(indent, text, span)

    def emit_globals(self, src: _Source) -> None:
        pc = PouCompiler(self.ctx, None, 1 << 30)
        fields: list[tuple[str, str, Optional[Span]]] = [("now", "0", None)]
        fields += [(f"v_{g.key}", pc.init_code(g.ty, g.init, g.span), g.span)
                   for g in self.ctx.globals.values() if g.location is None]
        inits: dict[str, VarInfo] = {}
        for info in self.ctx.pous.values():
            for v in info.vars.values():
                if v.location is not None and v.init is not None:
                    inits.setdefault(v.location, v)
        for g in self.ctx.globals.values():
            if g.location is not None and g.init is not None:
                inits[g.location] = g
        for addr, (ty, attr, span) in self.locations.items():
            v = inits.get(addr)
            fields.append((attr, pc.init_code(ty, v.init, v.span) if v is not None else default_code(ty), span))
        _storage_class(src, "C__G", fields)


def _storage_class(src: _Source, name: str, fields: list[tuple[str, str, Optional[Span]]],
                   span: Optional[Span] = None) -> None:
    """A slotted class whose __init__ gives every field (attribute, initial value code, ST span) its value."""
    src.add(0, f"class {name}:", span)
    src.add(1, f"__slots__ = {tuple(attr for attr, _c, _s in fields)!r}")
    src.add(1, "def __init__(self):")
    for attr, code, fspan in fields:
        src.add(2, f"self.{attr} = {code}", fspan)
    if not fields:
        src.add(2, "pass")


def st_span(field: T.StructField, filename: str) -> Span:
    init = field.init
    span = getattr(init, "span", None)
    return span or Span(filename, 1, 1)


def compile_st(text: str, filename: str, loop_limit: int) -> CompiledProject:
    return Compiler(filename, loop_limit).run(text)


def base_tick(tasks: list[TaskInfo]) -> int:
    tick = 0
    for t in tasks:
        tick = math.gcd(tick, t.interval_ms)
    return tick or 1
