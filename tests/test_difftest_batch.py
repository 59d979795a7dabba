"""The fixed-seed batch of random programs (issue 8): every one is equivalent after translation, on every executor found."""

from __future__ import annotations

import os

from tests.difftest.check import OK
from tests.difftest.run import Job, print_summary, program_seed, run_batch
from tests.difftest.check import available_backends

BATCH = 200
CYCLES = 200
MATIEC_EVERY = 20          # matiec compiles each program (seconds): a share of the batch where it is installed


def test_fixed_seed_batch_of_random_programs_is_equivalent(capsys):
    backends = available_backends()
    jobs = [Job(program_seed(1, i), 40, CYCLES, backends if i % MATIEC_EVERY == 0 else ("builtin",))
            for i in range(BATCH)]
    results = run_batch(jobs, os.cpu_count() or 1)
    with capsys.disabled():
        print_summary(results, 0.0)
    failures = [f"{job.program_seed}: {v.status} ({v.blame}) {v.detail}" for job, v, _ in results if v.status != OK]
    assert len(results) == BATCH
    assert not failures, "reduce with: python -m tests.difftest.run --only SEED --reduce\n" + "\n".join(failures)
    assert sum(v.cycles for _, v, _ in results) == BATCH * CYCLES
