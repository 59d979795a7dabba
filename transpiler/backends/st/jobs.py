"""Submit jobs (SUBM, RPLY, CAN) in the ST: one global queue, a block that works on it, and a second PROGRAM that
runs the jobs.

The control runs a submitted subprogram in the background; the simulation model the translation keeps (A-45, see
docs/assumptions.md) runs the queued jobs after the main program, in the order they were queued, each to its end,
within the same cycle (`submit_model = same_cycle`) or from the next cycle on (`next_cycle`). The ST does the same:

- The global `HH_JobQueue` (a `T_HH_JOB_QUEUE` STRUCT) holds up to 8 queued jobs with identifiers 1..255. SUBM,
  RPLY and CAN are calls of a local instance of the block `HH_JOB_QUEUE` (named `HH_Jobs` in every POU) with a
  command number and the queue as its VAR_IN_OUT `Q`; their result is its RESULT output. The queue is data, not
  a global FB instance, because writing the inputs of a global instance through VAR_EXTERNAL does not compile on
  OpenPLC v3 (its accessor macros differ from matiec's); a global passed to an FB's VAR_IN_OUT compiles on every
  target.
- The PROGRAM `HH_SubmitJobs` runs in the same task right after the main program (phase 5 of the cycle). Each
  job starts with cleared accumulators, index register, data stack and error markers, and the main program's
  values are put back afterwards, as the control keeps them apart.
- CAN of the running job ends that job at once; the translation supports it where the CAN is in the job's own
  subprogram (a RETURN), and reports E-UNSUPPORTED where it is in a subprogram the job calls.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

from transpiler.backends.iec_model import ArrayDim, DataType, IecVar, Pou, VarSection
from transpiler.frontend.flow import RoutineBodies, routines_entered
from transpiler.backends.st import exprs as E
from transpiler.backends.st import printer
from transpiler.backends.st import stmt as S
from transpiler.backends.st.routine import Unsupported
from transpiler.ir import CallTarget, Op, Program

QUEUE_FB = "HH_JOB_QUEUE"
QUEUE_TYPE, QUEUE_INTS, QUEUE_FLAGS = "T_HH_JOB_QUEUE", "T_HH_JOB_INTS", "T_HH_JOB_FLAGS"
QUEUE_DATA, QUEUE_INSTANCE = "HH_JobQueue", "HH_Jobs"   # the global queue, the block's instance in each POU
MAX_QUEUED = 8
MAX_ID = 255
# Commands of the queue block (its CMD input).
SUBMIT, REPLY, CANCEL, TAKE, ENDED, PHASE_END = 1, 2, 3, 4, 5, 6


@dataclasses.dataclass(frozen=True)
class JobPlan:
    """The program's job subprograms: their numbers in the queue, and where CAN can end the running job."""

    numbers: dict[tuple[int, int], int]          # routine key -> job number 1..N (order of the source)
    labels: dict[tuple[int, int], str]
    called_in_jobs: frozenset[tuple[int, int]]  # routines a job reaches by CM (CASE, fall-through)

    @property
    def used(self) -> bool:
        return bool(self.numbers)

    def routine(self, key: tuple[int, int], queue: Callable[[], "QueueAccess"]) -> "RoutineJobs":
        return RoutineJobs(self, key, queue)


@dataclasses.dataclass(frozen=True)
class QueueAccess:
    """How one POU reaches the queue: its own instance of the queue block, and the global queue it passes."""

    instance: str
    data: str                       # as the POU bodies name the global (GVL_Jobs.HH_JobQueue on a GVL target)

    def call(self, command: int, argument: tuple[str, E.Expr] | None = None, note: str | None = None) -> S.Call:
        args = (("CMD", E.int_const(command)),) + ((argument,) if argument is not None else ())
        return S.Call(self.instance, args + (("Q", E.var(self.data, QUEUE_TYPE)),), note)

    def result(self, hi: int) -> E.Expr:
        return E.Expr(f"{self.instance}.RESULT", "DINT", frozenset([E.base_name(self.instance)]), 0, hi)


class RoutineJobs:
    """What the translation of one routine needs to know about jobs: the queue, the job numbers, and whether a
    CAN there can end the running job with a RETURN (only in a job's own subprogram, when no job calls it: there
    the RETURN would end a callee, not the job)."""

    def __init__(self, plan: JobPlan, key: tuple[int, int], queue: Callable[[], QueueAccess]):
        self._plan = plan
        self._queue = queue
        self.is_job = key in plan.numbers
        self.called_in_job = key in plan.called_in_jobs

    @property
    def queue(self) -> QueueAccess:
        """The queue as this routine reaches it (declared on first use)."""
        return self._queue()

    def number(self, op: Op) -> int:
        if op.call is None or op.call.file < 0 or op.call.key not in self._plan.numbers:
            raise Unsupported("SUBM of a label that is not a subprogram of the project", op.span)
        return self._plan.numbers[op.call.key]


def plan_jobs(program: Program, bodies: RoutineBodies | None = None) -> JobPlan:
    """Number the SUBM targets of `program` and find the routines the jobs call."""
    bodies = bodies or RoutineBodies.of(program)
    entries = {r.key: r for r in program.routines}
    roots: dict[tuple[int, int], CallTarget] = {}
    for f in program.files:
        for op in f.ops:
            # A SUBM only in code that never runs (after a JP, in a job nothing queues) names no routine: no job.
            if op.code == "SUBM" and op.call is not None and op.call.file >= 0 and op.call.key in entries:
                roots.setdefault(op.call.key, op.call)
    numbers = {key: n for n, key in enumerate(sorted(roots), start=1)}
    reached: set[tuple[int, int]] = set()
    todo = list(roots.values())
    seen: set[tuple[int, int]] = set()
    while todo:
        r = todo.pop()
        if r.key in seen:
            continue
        seen.add(r.key)
        ops = program.files[r.file].ops
        for i in bodies(r):
            entered = routines_entered(ops[i])
            # Falling through into another routine's label runs that routine as a callee as well.
            if i != r.index and (r.file, i) in entries:
                entered.append(entries[(r.file, i)])
            for t in entered:
                reached.add(t.key)
                todo.append(entries.get(t.key, t))
    return JobPlan(numbers, {k: roots[k].label for k in numbers}, frozenset(reached))


@dataclasses.dataclass(frozen=True)
class OwnValue:
    """A variable of which the main program and each job have their own value: saved before a job, set to
    `clear` for it, restored after it."""

    target: str                     # as the POU bodies name it
    clear: str
    typ: str


@dataclasses.dataclass(frozen=True)
class JobCall:
    """One job subprogram as the job runner calls it: its number in the queue, its FB instance and type."""

    number: int
    instance: str
    fb_type: str
    label: str                      # where it comes from, for the comment


def jobs_program(name: str, queue: QueueAccess, model: str, calls: list[JobCall], own: list[OwnValue],
                 stack_pointer: str | None, in_job: str | None, local_name: Callable[[str], str]) -> Pou:
    """The PROGRAM `name` that runs the queued jobs (`calls`, by job number); `own` are the variables each job has
    its own copy of; `stack_pointer` and `in_job` the data stack pointer and the in-job flag where the program has
    them; `local_name` gives unique names."""
    calls = sorted(calls, key=lambda c: c.number)
    saved = [(v, local_name(f"main_{E.unqualified(v.target).replace('[', '_').replace(']', '')}")) for v in own]
    command = queue.call
    result = queue.result(MAX_ID)
    body: list[S.Stmt] = [S.Assign(local, E.Expr(v.target, v.typ, frozenset([E.base_name(v.target)]), var=v.target))
                          for v, local in saved]
    body += [S.Assign(v.target, E.Expr(v.clear, v.typ)) for v, _ in saved]
    if stack_pointer is not None:
        body.append(S.Assign(stack_pointer, E.int_const(0, "INT")))
    if in_job is not None:
        body.append(S.Assign(in_job, E.bool_const(True)))
    body.append(S.Case(result, tuple(S.CaseBranch((c.number,), (S.Call(c.instance, note=c.label),)) for c in calls)))
    if in_job is not None:
        body.append(S.Assign(in_job, E.bool_const(False)))
    body += [S.Assign(v.target, E.var(local, v.typ)) for v, local in saved]
    body += [command(ENDED), command(TAKE)]
    pending = E.binop("<>", result, E.int_const(0), "BOOL", E.PREC_EQ, 0, 1)
    statements: list[S.Stmt] = [command(TAKE), S.While(pending, tuple(body))]
    if model != "same_cycle":
        statements.append(command(PHASE_END))
    local = [IecVar(queue.instance, QUEUE_FB, comment="works on the job queue")]
    local += [IecVar(c.instance, c.fb_type, comment=f"job {c.number}") for c in calls]
    local += [IecVar(local, v.typ, comment=f"the main program's {E.unqualified(v.target)} while a job runs")
              for v, local in saved]
    return printer.with_statements(Pou(name, "PROGRAM", (VarSection("VAR", tuple(local)),), "", comment=(
        "Phase 5 of the PLC cycle: the submit jobs the main program queued run now, one after the other, each to "
        "its end. A job starts with cleared accumulators, index register, data stack and error markers; the main "
        "program's are put back after it.")), statements)


def queue_types(model: str) -> list[DataType]:
    """The queue's STRUCT and the array types it is built of (named: the PLCopen XML needs named types). Every
    member starts at 0, so the STRUCT needs no initial values (not every target takes them)."""
    types = [DataType(QUEUE_INTS, "array", "INT", (ArrayDim(1, MAX_QUEUED),), comment="queued jobs (job queue)")]
    fields = [IecVar("QUEUED_JOB", QUEUE_INTS, comment="job number of each queued job, oldest first"),
              IecVar("QUEUED_ID", QUEUE_INTS, comment="its identifier")]
    if model != "same_cycle":
        types.append(DataType(QUEUE_FLAGS, "array", "BOOL", (ArrayDim(1, MAX_QUEUED),),
                              comment="flags of the queued jobs (job queue)"))
        fields.append(IecVar("QUEUED_NOW", QUEUE_FLAGS, comment="queued in this cycle"))
    fields += [IecVar("COUNT", "INT", comment="queued jobs"),
               IecVar("LAST_ID", "INT", comment="identifier the last SUBM gave, 0 before the first"),
               IecVar("RUNNING_ID", "INT", comment="identifier of the running job, 0 when none runs")]
    types.append(DataType(QUEUE_TYPE, "struct", fields=tuple(fields), comment="the submit-job queue"))
    return types


def queue_fb(model: str) -> Pou:
    """HH_JOB_QUEUE for `submit_model` `model` (same_cycle: a job runs in the cycle that queued it): the commands
    on the queue it is given (the block keeps no state of its own)."""
    # Kept whole (~100 lines): the block's ST listing, one command per CASE entry, read best in one piece.
    next_cycle = model != "same_cycle"
    shift = ["Q.QUEUED_JOB[I] := Q.QUEUED_JOB[I + 1];", "Q.QUEUED_ID[I] := Q.QUEUED_ID[I + 1];"]
    keep = ["Q.QUEUED_JOB[K] := Q.QUEUED_JOB[I];", "Q.QUEUED_ID[K] := Q.QUEUED_ID[I];"]
    queue_now = ["Q.QUEUED_NOW[Q.COUNT] := TRUE;"] if next_cycle else []
    if next_cycle:
        shift.append("Q.QUEUED_NOW[I] := Q.QUEUED_NOW[I + 1];")
        keep.append("Q.QUEUED_NOW[K] := Q.QUEUED_NOW[I];")
    ready = "K = 0 AND NOT Q.QUEUED_NOW[I]" if next_cycle else "K = 0"

    def block(lines: list[str], depth: int) -> list[str]:
        return ["    " * depth + line for line in lines]

    body = [
        "CASE CMD OF",
        f"    {SUBMIT}: (* SUBM: queue job JOB *)",
        "        RESULT := 0;",
        f"        IF Q.RUNNING_ID = 0 AND Q.COUNT < {MAX_QUEUED} THEN",
        "            (* the next identifier that no queued job holds *)",
        f"            K := Q.LAST_ID MOD {MAX_ID} + 1;",
        "            REPEAT",
        "                FREE := TRUE;",
        "                FOR I := 1 TO Q.COUNT DO",
        "                    IF Q.QUEUED_ID[I] = K THEN",
        "                        FREE := FALSE;",
        "                    END_IF;",
        "                END_FOR;",
        "                IF NOT FREE THEN",
        f"                    K := K MOD {MAX_ID} + 1;",
        "                END_IF;",
        "            UNTIL FREE",
        "            END_REPEAT;",
        "            Q.LAST_ID := K;",
        "            Q.COUNT := Q.COUNT + 1;",
        "            Q.QUEUED_JOB[Q.COUNT] := JOB;",
        "            Q.QUEUED_ID[Q.COUNT] := K;",
        *block(queue_now, 3),
        "            RESULT := INT_TO_DINT(K);",
        "        END_IF;",
        f"    {REPLY}: (* RPLY: 1 running, 2 waiting in the queue, 0 finished or unknown *)",
        "        RESULT := 0;",
        "        IF Q.RUNNING_ID <> 0 AND INT_TO_DINT(Q.RUNNING_ID) = ID THEN",
        "            RESULT := 1;",
        "        ELSE",
        "            FOR I := 1 TO Q.COUNT DO",
        "                IF INT_TO_DINT(Q.QUEUED_ID[I]) = ID THEN",
        "                    RESULT := 2;",
        "                END_IF;",
        "            END_FOR;",
        "        END_IF;",
        f"    {CANCEL}: (* CAN: the job leaves the queue; RESULT 1 when it is the running one, which ends now *)",
        "        K := 0;",
        "        FOR I := 1 TO Q.COUNT DO",
        "            IF INT_TO_DINT(Q.QUEUED_ID[I]) <> ID THEN",
        "                K := K + 1;",
        *block(keep, 4),
        "            END_IF;",
        "        END_FOR;",
        "        Q.COUNT := K;",
        "        RESULT := 0;",
        "        IF Q.RUNNING_ID <> 0 AND INT_TO_DINT(Q.RUNNING_ID) = ID THEN",
        "            RESULT := 1;",
        "        END_IF;",
        f"    {TAKE}: (* the first queued job that may run now becomes the running one; RESULT its JOB, 0 none *)",
        "        RESULT := 0;",
        "        K := 0;",
        "        FOR I := 1 TO Q.COUNT DO",
        f"            IF {ready} THEN",
        "                K := I;",
        "            END_IF;",
        "        END_FOR;",
        "        IF K > 0 THEN",
        "            RESULT := INT_TO_DINT(Q.QUEUED_JOB[K]);",
        "            Q.RUNNING_ID := Q.QUEUED_ID[K];",
        "            FOR I := K TO Q.COUNT - 1 DO",
        *block(shift, 4),
        "            END_FOR;",
        "            Q.COUNT := Q.COUNT - 1;",
        "        END_IF;",
        f"    {ENDED}: (* the running job reached its end *)",
        "        Q.RUNNING_ID := 0;",
    ]
    if next_cycle:
        body += [f"    {PHASE_END}: (* end of the job phase: what was queued in this cycle may run in the next one *)",
                 "        FOR I := 1 TO Q.COUNT DO",
                 "            Q.QUEUED_NOW[I] := FALSE;",
                 "        END_FOR;"]
    body.append("END_CASE;")
    body = _while_loops(body)
    model = ("in the cycle that queued them" if not next_cycle else "from the cycle after the one that queued them")
    return Pou(QUEUE_FB, "FUNCTION_BLOCK", (
        VarSection("VAR_INPUT", (
            IecVar("CMD", "INT", comment=f"{SUBMIT} SUBM, {REPLY} RPLY, {CANCEL} CAN, {TAKE} take the next job, "
                                         f"{ENDED} the running job ended" + (f", {PHASE_END} end of the job phase"
                                                                             if next_cycle else "")),
            IecVar("JOB", "INT", comment="SUBM: number of the job subprogram"),
            IecVar("ID", "DINT", comment="RPLY, CAN: job identifier"))),
        VarSection("VAR_OUTPUT", (IecVar("RESULT", "DINT", comment="the command's result (see each command)"),)),
        VarSection("VAR_IN_OUT", (IecVar("Q", QUEUE_TYPE, comment="the job queue (the global HH_JobQueue)"),)),
        VarSection("VAR", (IecVar("I", "INT"), IecVar("K", "INT"), IecVar("FREE", "BOOL"))),
    ), "\n".join(body), comment=(
        f"The control's submit-job queue (A-45, see docs/assumptions.md): up to {MAX_QUEUED} jobs, identifiers "
        f"1..{MAX_ID} counted on and skipping those in use; SUBM inside a running job or with a full queue gives "
        f"0. Queued jobs run one after the other, each to its end, {model}."))


def _while_loops(lines: list[str]) -> list[str]:
    """The listing's counted loops `FOR I := a TO b DO ... END_FOR;` written as WHILE loops: matiec runs a FOR
    body zero times when the range holds a single value (FOR I := 1 TO 1)."""
    out: list[str] = []
    for line in lines:
        indent = line[:len(line) - len(line.lstrip())]
        text = line.strip()
        if text.startswith("FOR I := ") and text.endswith(" DO"):
            start, end = text[len("FOR I := "):-len(" DO")].split(" TO ")
            out += [f"{indent}I := {start};", f"{indent}WHILE I <= {end} DO"]
        elif text == "END_FOR;":
            out += [f"{indent}    I := I + 1;", f"{indent}END_WHILE;"]
        else:
            out.append(line)
    return out
