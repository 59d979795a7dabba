"""Designators: variables, direct addresses, struct fields and FB members, array elements, and lvalues."""

from __future__ import annotations

from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.model import VarInfo
from transpiler.exec.stexec.pou_base import PouBase
from transpiler.exec.stexec.pycode import ERR_EX, P_ATOM, P_UNARY, Ex, const_ex, normalise_address, paren


class AccessCompiler(PouBase):
    """Designators: variables, direct addresses, struct fields and FB members, array elements, and lvalues."""

    def name_ex(self, node: n.Name) -> Ex:
        key = node.name.lower()
        v = self.lookup(key)
        if v is not None:
            return self.var_ex(v)
        if key in ("true", "false"):
            return const_ex(key == "true", T.BOOL)
        if self.pou is not None and self.pou.prelude and key == "__current_time":
            return Ex("G.now", T.TIME)
        enums = self.ctx.enum_values.get(key, [])
        enums = [(e, i) for e, i in enums if self.ctx.types[e.name.lower()][2] < self.ordinal]
        if len(enums) == 1:
            return const_ex(enums[0][1], enums[0][0])
        if len(enums) > 1:
            return self.err(node.span, f"enum value '{node.name}' is ambiguous; write Type#{node.name}")
        if key in self.ctx.globals:
            return self.err(node.span, f"'{node.name}' is a global variable; declare it in a VAR_EXTERNAL block "
                                       "to use it here")
        return self.err(node.span, f"undeclared variable '{node.name}'")

    def var_ex(self, v: VarInfo) -> Ex:
        const = v.const_value if v.constant else None
        code = self.var_code(v)
        prec = P_UNARY if code.startswith("-") else P_ATOM
        writable, why = True, ""
        if v.constant:
            writable, why = False, f"'{v.name}' is a CONSTANT"
        elif isinstance(v.ty, T.FbT):
            writable, why = False, f"'{v.name}' is a function block instance"
        is_global = v.kind == "external"
        return Ex(code, v.ty, prec, True, const, v, writable, why, is_global)

    def addr_ex(self, node: n.Addr) -> Ex:
        addr = normalise_address(node.address)
        if addr is None:
            return self.err(node.span, f"invalid address '{node.address}'")
        if self.pou is not None:
            for v in self.pou.vars.values():
                if v.location == addr:
                    return self.var_ex(v)
        if self.pou is None or self.pou.kind != "program" or self.ctx.use_address is None:
            return self.err(node.span, f"directly represented variable {addr} outside a PROGRAM")
        found = self.ctx.use_address(addr, node.span)
        if found is None:
            return ERR_EX
        ty, attr = found
        return Ex(f"G.{attr}", ty, P_ATOM, True, None, None, True)

    def field_ex(self, node: n.Field) -> Ex:
        base_ex = self.expr(node.base, allow_fb=True)
        if base_ex.ty is T.ERR:
            return ERR_EX
        key = node.name.lower()
        bty = T.base(base_ex.ty)
        if isinstance(bty, T.StructT):
            f = bty.fields.get(key)
            if f is None:
                return self.err(node.span, f"struct {bty.name} has no field '{node.name}'")
            return Ex(f"{paren(base_ex, P_ATOM)}.v_{key}", f.ty, P_ATOM, True, None, base_ex.var,
                      base_ex.writable, base_ex.why_readonly, base_ex.is_global)
        if isinstance(bty, T.FbT):
            fv = bty.pou.vars.get(key)
            if fv is None or fv.kind in ("external", "temp") or fv.location is not None:
                return self.err(node.span, f"function block {bty.name} has no parameter '{node.name}'")
            writable, why = base_ex.writable or isinstance(base_ex.ty, T.FbT), ""
            if fv.kind == "output":
                writable, why = False, f"'{node.name}' is an output of {bty.name} (only the FB writes it)"
            elif fv.kind == "var":
                writable, why = False, f"'{node.name}' is a private variable of {bty.name}"
            return Ex(f"{paren(base_ex, P_ATOM)}.v_{key}", fv.ty, P_ATOM, True, None, base_ex.var,
                      writable, why, base_ex.is_global)
        return self.err(node.span, f"'.{node.name}' applied to a value of type {base_ex.ty}, which has no fields "
                                   "(bit access w.n is not supported by matiec; use SHR and AND)")

    def index_ex(self, node: n.Index) -> Ex:
        base_ex = self.expr(node.base)
        if base_ex.ty is T.ERR:
            return ERR_EX
        aty = T.base(base_ex.ty)
        if not isinstance(aty, T.ArrayT):
            return self.err(node.span, f"index applied to a value of type {base_ex.ty}, which is not an array")
        if len(node.indices) != len(aty.dims):
            return self.err(node.span, f"array {aty.name} has {len(aty.dims)} dimension(s), "
                                       f"{len(node.indices)} index(es) given")
        parts, checks, temps, consts = [], [], [], []
        strides = aty.strides()
        for idx_node, (lo, hi), stride in zip(node.indices, aty.dims, strides):
            ix = self.expr(idx_node)
            if ix.ty is T.ERR:
                return ERR_EX
            if not (T.is_int(ix.ty) or (isinstance(ix.ty, T.LitType) and ix.ty.cat == "int")):
                return self.err(idx_node.span, f"array index must be an integer (INT, DINT, ...), not {ix.ty}")
            ix = self.val(ix)
            if ix.const is not None:
                if not lo <= ix.const <= hi:
                    return self.err(idx_node.span, f"array index {ix.const} outside {lo}..{hi}")
                consts.append((ix.const - lo) * stride)
                temps.append(str(ix.const))
                continue
            t = self.temp("_i")
            checks.append(f"{lo} <= ({t} := {ix.code}) <= {hi}")
            term = f"{t} - {lo}" if lo else t
            parts.append(f"({term}) * {stride}" if stride != 1 else term)
            temps.append(t)
        offset = sum(consts)
        if offset or not parts:
            parts.append(str(offset))
        flat = " + ".join(parts)
        if checks:
            cond = " and ".join(checks) if len(checks) == 1 else " & ".join(f"({c})" for c in checks)
            dims = repr(aty.dims)
            flat = f"{flat} if {cond} else _oob(({', '.join(temps)},), {dims})"
        return Ex(f"{paren(base_ex, P_ATOM)}[{flat}]", aty.elem, P_ATOM, True, None, base_ex.var,
                  base_ex.writable, base_ex.why_readonly, base_ex.is_global)

    def lvalue(self, node: n.Expr) -> Ex:
        if not isinstance(node, (n.Name, n.Addr, n.Field, n.Index)):
            return self.err(node.span, "assignment to an expression or a literal value is not allowed")
        ex = self.expr(node, allow_fb=True)
        if ex.ty is T.ERR:
            return ex
        if isinstance(node, n.Name) and ex.var is None:
            return self.err(node.span, f"'{node.name}' cannot be assigned")
        if not ex.writable:
            return self.err(node.span, f"assignment not allowed: {ex.why_readonly}")
        if isinstance(ex.ty, T.FbT):
            return self.err(node.span, "a function block instance cannot be assigned")
        return ex
