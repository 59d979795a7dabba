"""SUBM, RPLY and CAN: calls of the global job queue block (jobs.py); results arrive in the word accumulator."""

from __future__ import annotations

from transpiler.ir import Op
from transpiler.backends.st import exprs as E
from transpiler.backends.st import jobs
from transpiler.backends.st.routine import ExecutorPart, Unsupported


class JobOpsMixin(ExecutorPart):
    """op_* handlers of the submit-job commands."""

    def _jobs(self, op: Op) -> "jobs.RoutineJobs":
        if self.ctx.jobs is None:
            raise Unsupported(f"submit jobs ({op.mnemonic})", op.span)
        return self.ctx.jobs

    def _queue(self, op: Op, args: str) -> str:
        """Emit one call of the queue block (values in flight that read its RESULT are saved first)."""
        queue = self._jobs(op).queue
        self.prepare_write(queue.upper())
        span = op.span
        self.ctx.out.line(f"{queue}({args}); (* {op.mnemonic} {span.file}:{span.line} *)")
        return queue

    def _result(self, queue: str, hi: int) -> E.Expr:
        return E.Expr(f"{queue}.RESULT", "DINT", frozenset([queue.upper()]), 0, hi)

    def op_SUBM(self, op: Op) -> None:
        number = self._jobs(op).number(op)
        queue = self._queue(op, f"CMD := {jobs.SUBMIT}, JOB := {number}")
        self.s.set("WA", self._result(queue, jobs.MAX_ID))

    def op_RPLY(self, op: Op) -> None:
        ident = E.to_dint(self.value(op.operand))
        queue = self._queue(op, f"CMD := {jobs.REPLY}, ID := {ident.text}")
        self.s.set("WA", self._result(queue, 2))

    def op_CAN(self, op: Op) -> None:
        routine = self._jobs(op)
        if routine.called_in_job:
            raise Unsupported("CAN in a subprogram that a submit job calls (cancelling the running job from there "
                              "would have to end its callers too)", op.span)
        ident = E.to_dint(self.value(op.operand))
        queue = self._queue(op, f"CMD := {jobs.CANCEL}, ID := {ident.text}")
        if not routine.is_job:
            return      # only a job can be the running one
        # Nothing of a job runs after it cancelled itself.
        self.ctx.out.line(f"IF {queue}.RESULT = 1 THEN")
        self.ctx.out.line("    RETURN; (* the running job cancelled itself *)")
        self.ctx.out.line("END_IF;")
