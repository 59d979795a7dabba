"""Where hh2iec's data files are at run time: the ST templates and the C sources of the runtime shim.

The repository keeps them at its top level (templates/, runtime_shim/); a wheel carries the same files inside the
package, under transpiler/_data/ (setup.py copies them there while building). The installed copy wins; a checkout
or an editable install, which has no _data folder, falls back to the folders beside the package. Also the per-user
cache folder, where things built on first use (the shim library) go, because an installed package may be read-only.
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

PACKAGED_DATA = "_data"
"""Folder inside the installed package that holds the copies of templates/ and runtime_shim/."""

DATA_FOLDERS = ("templates", "runtime_shim")


class DataMissing(FileNotFoundError):
    """A data folder of hh2iec is neither in the installed package nor in a checkout: a broken installation."""


def data_dir(name: str) -> Path:
    """The folder `name` (one of DATA_FOLDERS) as installed with the package, else from the checkout."""
    if name not in DATA_FOLDERS:
        raise ValueError(f"unknown data folder {name!r} (known: {', '.join(DATA_FOLDERS)})")
    packaged = resources.files("transpiler").joinpath(PACKAGED_DATA, name)
    # A regular install gives a real folder; hh2iec needs real files (jinja2 loader, the C compiler), so a
    # zipped package is not supported and falls through to the error below.
    if isinstance(packaged, Path) and packaged.is_dir():
        return packaged
    checkout = Path(__file__).resolve().parent.parent / name
    if checkout.is_dir():
        return checkout
    raise DataMissing(f"hh2iec's data folder '{name}' is missing (looked in {packaged} and {checkout}); "
                      "reinstall hh2iec")


def cache_dir() -> Path:
    """The per-user cache of hh2iec: $HH2IEC_CACHE, else $XDG_CACHE_HOME/hh2iec, else ~/.cache/hh2iec."""
    configured = os.environ.get("HH2IEC_CACHE")
    if configured:
        return Path(configured)
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg and Path(xdg).is_absolute() else Path.home() / ".cache"
    return base / "hh2iec"
