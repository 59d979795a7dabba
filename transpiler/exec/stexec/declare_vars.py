"""Declarations of variables, POUs and globals: located variables, constants, VAR_EXTERNAL against VAR_GLOBAL."""

from __future__ import annotations

from typing import Optional

from transpiler.exec.stexec import nodes as n
from transpiler.exec.stexec import typesys as T
from transpiler.exec.stexec.codegen import PouCompiler
from transpiler.exec.stexec.compiler_base import ALLOWED_KINDS, KIND_NAMES, SIZE_TYPE, CompilerBase
from transpiler.exec.stexec.model import PouInfo, VarInfo
from transpiler.exec.stexec.pycode import normalise_address, storage_attr


class VarDeclarer(CompilerBase):
    """Declarations of variables, POUs and globals: located variables, constants, VAR_EXTERNAL against VAR_GLOBAL."""

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
                                  f"{KIND_NAMES[block.kind]}")
            return None
        b = T.base(ty)
        size = SIZE_TYPE[addr[2]].bits
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
            if block.kind not in ALLOWED_KINDS[node.kind]:
                if block.kind == "external" and node.kind == "function":
                    self.error(block.span, "unexpected external variable(s) declaration in function declaration "
                                           "(functions cannot see globals; use a FUNCTION_BLOCK with VAR_EXTERNAL)")
                else:
                    self.error(block.span, f"{KIND_NAMES[block.kind]} is not allowed in a "
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
        if node.kind in ("program", "function_block") and not node.blocks and not prelude:
            kind = node.kind.replace("_", " ").upper()
            self.error(node.span, f"{kind} {node.name} declares no variable at all; matiec rejects it (declare one)")
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
