"""SUBM, RPLY and CAN: calls of the job queue block on the global queue (jobs.py); results arrive in the word
accumulator."""

from __future__ import annotations

from transpiler.ir import Op
from transpiler.backends.st import exprs as E
from transpiler.backends.st import stmt as S
from transpiler.backends.st import jobs
from transpiler.backends.st.routine import ExecutorPart, Unsupported, tag


class JobOpsMixin(ExecutorPart):
    """op_* handlers of the submit-job commands."""

    def _jobs(self, op: Op) -> "jobs.RoutineJobs":
        if self.ctx.jobs is None:
            raise Unsupported(f"submit jobs ({op.mnemonic})", op.span)
        return self.ctx.jobs

    def _queue(self, op: Op, command: int, argument: tuple[str, E.Expr]) -> "jobs.QueueAccess":
        """Emit one call of the queue block (values in flight that read its RESULT are saved first)."""
        queue = self._jobs(op).queue
        self.prepare_write(E.base_name(queue.instance))
        self.ctx.out.add(queue.call(command, argument, f"{op.mnemonic} {tag(op.span)}"))
        return queue

    def op_SUBM(self, op: Op) -> None:
        number = self._jobs(op).number(op)
        self.drop(["WA"])           # the result replaces it: a value in flight there is saved for nobody
        queue = self._queue(op, jobs.SUBMIT, ("JOB", E.int_const(number)))
        self.s.set("WA", queue.result(jobs.MAX_ID))

    def op_RPLY(self, op: Op) -> None:
        ident = E.to_dint(self.value(op.operand))
        self.drop(["WA"])           # as in SUBM
        queue = self._queue(op, jobs.REPLY, ("ID", ident))
        self.s.set("WA", queue.result(2))

    def op_CAN(self, op: Op) -> None:
        routine = self._jobs(op)
        if routine.called_in_job:
            raise Unsupported("CAN in a subprogram that a submit job calls (cancelling the running job from there "
                              "would have to end its callers too)", op.span)
        ident = E.to_dint(self.value(op.operand))
        queue = self._queue(op, jobs.CANCEL, ("ID", ident))
        if not routine.is_job:
            return      # only a job can be the running one
        # Nothing of a job runs after it cancelled itself.
        cancelled = E.binop("=", queue.result(2), E.int_const(1), "BOOL", E.PREC_EQ, 0, 1)
        self.ctx.out.add(S.If(cancelled, (S.Return("the running job cancelled itself"),)))
