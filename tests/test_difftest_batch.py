"""The fixed-seed batch of random programs (issue 8): every one is equivalent after translation, on every executor found."""

from __future__ import annotations

import os

from tests.difftest.check import PASSING, available_backends
from tests.difftest.run import Job, print_summary, program_seed, run_batch

BATCH = 200
CYCLES = 200
MATIEC_EVERY = 20          # matiec compiles each program (seconds): a share of the batch where it is installed
# Programs of this batch that expose a bug not fixed yet (program seed -> finding). The batch must fail on exactly
# these: a new failure fails the test, and so does a fix that was not recorded here.
KNOWN_OPEN: dict[int, str] = {}


def test_fixed_seed_batch_of_random_programs_is_equivalent(capsys):
    backends = available_backends()
    jobs = [Job(program_seed(1, i), 40, CYCLES, backends if i % MATIEC_EVERY == 0 else ("builtin",))
            for i in range(BATCH)]
    results = run_batch(jobs, os.cpu_count() or 1)
    with capsys.disabled():
        print_summary(results, 0.0)
    failures = {job.program_seed: f"{v.status} ({v.blame}) {v.detail}" for job, v, _ in results if v.status not in PASSING}
    assert len(results) == BATCH
    new = {seed: text for seed, text in failures.items() if seed not in KNOWN_OPEN}
    assert not new, "reduce with: python -m tests.difftest.run --only SEED --reduce\n" + "\n".join(
        f"{seed}: {text}" for seed, text in new.items())
    assert set(KNOWN_OPEN) == set(failures), "fixed: remove from KNOWN_OPEN: " + str(set(KNOWN_OPEN) - set(failures))
    passed = [v for job, v, _ in results if job.program_seed not in KNOWN_OPEN]
    assert sum(v.cycles for v in passed) == len(passed) * CYCLES
