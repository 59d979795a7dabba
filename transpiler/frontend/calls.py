"""Labels and calls: GLOBAL exports, linking of jumps, calls and CASE entries to their labels, the call graph (recursion, depth)."""

from __future__ import annotations

from transpiler.diagnostics import Diagnostics, Span
from transpiler.frontend.flow import RoutineBodies
from transpiler.frontend.lowering import FileLowering
from transpiler.frontend.symbols import folded_key
from transpiler.ir import CallTarget, FileCode
from transpiler.language.semantics import Semantics
from transpiler.records import replaced

_Key = tuple[int, int]                                  # (file index, op index) of a routine entry
_Edges = dict[_Key, list[tuple[CallTarget, Span]]]      # callee and the span of the call
_CALLS = frozenset({"CALL", "CALLT", "CALLF"})


def exports_of(lowerings: list[FileLowering], diags: Diagnostics) -> dict[str, CallTarget]:
    exports: dict[str, CallTarget] = {}
    where: dict[str, Span] = {}
    for low in lowerings:
        for g in low.globals:
            if g.name not in low.labels:
                if g.name not in low.src.broken_labels:
                    diags.report("E-SYM-GLOBAL-UNDEF", g.span, f"GLOBAL {g.name}: no such label in this file")
                continue
            if g.name in exports and exports[g.name].file != low.file_index:
                diags.report("E-SYM-DUP-GLOBAL", g.span, f"label {g.name} is also exported at {where[g.name]}")
                continue
            exports[g.name] = CallTarget(low.file_index, low.labels[g.name], g.name)
            where[g.name] = g.span
    return exports


def link(low: FileLowering, lowerings: list[FileLowering], exports: dict[str, CallTarget], diags: Diagnostics,
          labels_incomplete: bool = False) -> None:
    if low.semantics["symbol_case"] == "insensitive":       # labels are looked up ignoring case too
        def spelled(name: str, table: dict) -> str:
            return name if name in table else folded_key(table, name) or name
    else:
        def spelled(name: str, table: dict) -> str:
            return name

    def target(name: str, span: Span) -> CallTarget | None:
        name = spelled(name, low.labels)
        if name not in low.labels:
            name = spelled(name, low.externs)
        if name in low.externs:
            name = spelled(name, exports)
        if name in low.labels:
            return CallTarget(low.file_index, low.labels[name], name)
        if name in low.externs:
            found = exports.get(name)
            if found is not None:
                return found
            unresolved_extern(name, span)
            return None
        if name in low.src.broken_labels:   # its LBL line was rejected already
            return None
        elsewhere = [o.src.path for o in lowerings if name in o.labels]
        if name in exports:
            hint = f" ({elsewhere[0] if elsewhere else 'a used module'} exports it with GLOBAL: add EXTERN {name} here)"
        elif elsewhere:
            hint = f" (it is defined in {elsewhere[0]}: add GLOBAL {name} there and EXTERN {name} here)"
        else:
            hint = ""
        diags.report("E-SYM-UNRESOLVED", span, f"label {name} is not defined in this file{hint}")
        return None

    reported: set[str] = set()

    def unresolved_extern(name: str, span: Span) -> None:
        # (not when the module that would export it is unreadable, or its LBL line was rejected)
        reported.add(name)
        if labels_incomplete or any(name in o.src.broken_labels for o in lowerings):
            return
        elsewhere = [o.src.path for o in lowerings if name in o.labels and o is not low]
        hint = f" (it is defined in {elsewhere[0]}: add GLOBAL {name} there)" if elsewhere else ""
        diags.report("E-SYM-UNRESOLVED", span, f"EXTERN {name} is not exported with GLOBAL by any used module{hint}")

    for index, name, span in low.pending_calls:
        t = target(name, span)
        if t is not None:
            low.ops[index] = replaced(low.ops[index], call=t)
    case_targets: dict[int, list[CallTarget]] = {}
    for index, entry, name, span in low.pending_case:          # entries arrive in table order
        t = target(name, span)
        case_targets.setdefault(index, []).append(t if t is not None else CallTarget(label=name))
    for index, targets in case_targets.items():
        low.ops[index] = replaced(low.ops[index], case_targets=tuple(targets))
    for name, extern in low.externs.items():
        # an EXTERN that nothing calls still names a label no module exports (spec: E-SYM-UNRESOLVED)
        if name not in reported and name not in low.labels and spelled(name, exports) not in exports:
            unresolved_extern(name, extern.span)
    for index, name, span in low.pending_jumps:
        name = spelled(name, low.labels)
        if name in low.labels:
            low.ops[index] = replaced(low.ops[index], target=low.labels[name])
        elif name not in low.src.broken_labels:
            elsewhere = [o.src.path for o in lowerings if name in o.labels]
            where = f"; it is in {elsewhere[0]} (jumps stay inside a file, A-31)" if elsewhere else ""
            diags.report("E-JUMP-SCOPE", span, f"jump target {name} is not a label of this file{where}")


def call_graph(files: tuple[FileCode, ...], semantics: Semantics, diags: Diagnostics, bodies: RoutineBodies
               ) -> tuple[tuple[CallTarget, ...], int]:
    """The routines reached from the main program and SUBM jobs, and the static call depth; reports recursion and depth.
    `bodies` keeps the body of the main program and of each routine reached."""
    nodes, edges, roots = _call_edges(files, bodies)
    recursive = _report_recursion(_strong_components(edges), nodes, edges, diags)
    depth_limit = int(semantics["call_depth"])
    depth = _longest_paths(edges, recursive)
    max_depth = max((depth.get(r.key, 0) for r in roots), default=0)
    if max_depth > depth_limit and not recursive:
        diags.report("E-CALL-DEPTH", files[0].ops[0].span if files[0].ops else Span(files[0].path, 1, 1),
                    f"static call depth {max_depth} exceeds the limit {depth_limit} (A-29)")
    routines = tuple(sorted((n for n in nodes.values()), key=lambda t: (t.file, t.index)))
    return routines, max_depth


def _call_edges(files: tuple[FileCode, ...], bodies: RoutineBodies
                ) -> tuple[dict[_Key, CallTarget], _Edges, list[CallTarget]]:
    """Walk the routine bodies from the main program: the routines found, the calls of each, and the roots (main, SUBM)."""
    main = CallTarget(0, 0, "<main>")
    nodes: dict[tuple[int, int], CallTarget] = {}
    edges: _Edges = {}
    roots = [main] if files and files[0].ops else []
    todo = list(roots)
    while todo:
        node = todo.pop()
        if node.key in edges:
            continue
        out: list[tuple[CallTarget, Span]] = []        # callee and the span of the call
        ops = files[node.file].ops
        for i in bodies(node):
            op = ops[i]
            code = op.code
            if code in _CALLS:
                if op.call is None or op.call.is_module or op.call.file < 0:
                    continue
                callees = [(op.call, op.span)]
            elif code == "CASE":
                # each entry is a call site of its own, located at its CM line
                callees = [(t, op.case_notes[k][0] if k < len(op.case_notes) else op.span)
                           for k, t in enumerate(op.case_targets) if t is not None and t.file >= 0]
            else:
                if code == "SUBM" and op.call is not None and op.call.file >= 0 and op.call.key not in nodes:
                    nodes[op.call.key] = op.call
                    roots.append(op.call)
                    todo.append(op.call)
                continue
            for c, call_span in callees:
                out.append((c, call_span))
                if c.key not in nodes:
                    nodes[c.key] = c
                    todo.append(c)
        edges[node.key] = out
    return nodes, edges, roots


def _strong_components(edges: _Edges) -> list[list[_Key]]:
    """Strongly connected components of the call graph (Tarjan's algorithm, iterative: no recursion limit)."""
    index_of: dict[tuple[int, int], int] = {}
    low: dict[tuple[int, int], int] = {}
    on_stack: set[tuple[int, int]] = set()
    stack: list[tuple[int, int]] = []
    sccs: list[list[tuple[int, int]]] = []

    def strong(v: tuple[int, int]) -> None:
        work: list[tuple[tuple[int, int], int]] = []

        def enter(w: tuple[int, int]) -> None:
            index_of[w] = low[w] = len(index_of)      # visit order: nodes are numbered as they are entered
            stack.append(w)
            on_stack.add(w)
            work.append((w, 0))

        enter(v)
        while work:
            node, pos = work[-1]
            succ = edges.get(node, [])
            if pos < len(succ):
                work[-1] = (node, pos + 1)
                w = succ[pos][0].key
                if w not in index_of:
                    enter(w)
                elif w in on_stack:
                    low[node] = min(low[node], index_of[w])
                continue
            work.pop()
            if work:
                parent = work[-1][0]
                low[parent] = min(low[parent], low[node])
            if low[node] == index_of[node]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == node:
                        break
                sccs.append(comp)

    for key in list(edges):
        if key not in index_of:
            strong(key)
    return sccs


def _report_recursion(sccs: list[list[_Key]], nodes: dict[_Key, CallTarget], edges: _Edges,
                      diags: Diagnostics) -> set[_Key]:
    """Report each component with a cycle once; the routines in such components."""
    recursive: set[tuple[int, int]] = set()
    for comp in sccs:
        members = set(comp)
        # 17b.11: at the call that closes the cycle, the first one in file order (program file, then line)
        calls = [(k[0], span.line, span) for k in comp for (c, span) in edges.get(k, []) if c.key in members]
        if calls:
            recursive |= members
            span = min(calls, key=lambda t: (t[0], t[1]))[2]
            names = ", ".join(sorted(nodes[k].label if k in nodes else "<main>" for k in comp))
            diags.report("E-CALL-RECURSION", span, f"recursive calls between {names} (A-29)")
    return recursive


def _longest_paths(edges: dict[tuple[int, int], list[tuple[CallTarget, Span]]],
                   skip: set[tuple[int, int]]) -> dict[tuple[int, int], int]:
    """Longest call chain below each node of the (acyclic once `skip` is removed) call graph."""
    depth: dict[tuple[int, int], int] = {}
    for root in edges:
        if root in depth:
            continue
        stack = [(root, False)]
        while stack:
            node, expanded = stack.pop()
            if node in depth:
                continue
            callees = [c.key for c, _ in edges.get(node, []) if c.key not in skip and c.key != node]
            if expanded:
                depth[node] = max((depth.get(c, 0) + 1 for c in callees), default=0)
                continue
            stack.append((node, True))
            stack.extend((c, False) for c in callees if c not in depth)
    return depth
