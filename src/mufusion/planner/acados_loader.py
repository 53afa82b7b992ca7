"""Load acados from the PyPI wheel ``comma-deps-acados``: the one place for its plumbing.

The wheel's shared libraries carry no RUNPATH and its template expects three environment variables
and a symlink inside the package (see docs/planner.md). :func:`load_acados_template` sets all of
that up once and returns the ``acados_template`` module, or raises :class:`AcadosUnavailable`
so the caller can fall back to the CasADi backend. :func:`build_lock` keeps processes that share
the solver cache (campaign workers, parallel test workers) from building one solver at once.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import io
import logging
import os
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

_log = logging.getLogger(__name__)

# Load order matters: each library needs the ones before it.
_LIBRARIES = ("libblasfeo.so", "libhpipm.so", "libqpOASES_e.so", "libacados.so")


class AcadosUnavailable(RuntimeError):
    """acados cannot be used here (no wheel, missing libraries or compiler)."""


def cache_dir() -> Path:
    """Directory for generated solvers: ``$MUFUSION_CACHE_DIR`` or ``~/.cache/mufusion/acados``."""
    env = os.environ.get("MUFUSION_CACHE_DIR")
    return Path(env) if env else Path.home() / ".cache" / "mufusion" / "acados"


@contextlib.contextmanager
def build_lock(export: Path) -> Iterator[None]:
    """Hold an exclusive lock on the solver directory ``export`` (created if missing).

    Check for the compiled solver and build it inside the lock: a second process that needs the
    same solver waits for the first one's build and then finds it, instead of generating and
    compiling into the same files at once (interleaved object files, or a library loaded while
    the linker still writes it). The generated library names its directory by absolute path, so
    building elsewhere and renaming is not an option. The lock is ``flock`` on ``.build.lock``
    in ``export``: the kernel releases it when its holder exits, even killed mid-build. A
    directory that exists but cannot be written (a cache built elsewhere and shared read-only) is
    used without the lock: nothing can be built there, so there is nothing to wait for.

    Raises
    ------
    AcadosUnavailable
        If the directory or its lock file cannot be created.
    """
    import fcntl  # POSIX only, like the acados wheel itself

    try:
        export.mkdir(parents=True, exist_ok=True)
        handle = open(export / ".build.lock", "a")
    except OSError as exc:
        if export.is_dir() and not os.access(export, os.W_OK):
            yield
            return
        raise AcadosUnavailable(f"cannot lock the solver directory {export}: {exc}") from exc
    with handle:  # closing the descriptor releases the lock
        fcntl.flock(handle, fcntl.LOCK_EX)
        yield


@functools.lru_cache(maxsize=1)
def load_acados_template() -> ModuleType:
    """Prepare the environment and import ``acados_template``.

    Returns
    -------
    module
        The ``acados_template`` module.

    Raises
    ------
    AcadosUnavailable
        If the wheel is missing or its libraries cannot be loaded.
    """
    try:
        import acados
    except ImportError as exc:
        raise AcadosUnavailable("the comma-deps-acados wheel is not installed") from exc
    install = Path(acados.DIR)
    os.environ.setdefault("ACADOS_SOURCE_DIR", str(install))
    os.environ.setdefault("ACADOS_PYTHON_INTERFACE_PATH", str(acados.TEMPLATE_DIR))
    os.environ.setdefault("TERA_PATH", str(acados.TERA_PATH))
    try:
        for name in _LIBRARIES:
            ctypes.CDLL(str(install / "lib" / name), mode=ctypes.RTLD_GLOBAL)
    except OSError as exc:
        raise AcadosUnavailable(f"acados libraries failed to load: {exc}") from exc
    # The template prints a CasADi-version notice on import (it is tested against older CasADi;
    # code generation works with ours, see docs/planner.md); it is noise in every run's output.
    with contextlib.redirect_stdout(io.StringIO()):
        try:
            import acados_template
        except ImportError:
            try:
                from acados import acados_template  # type: ignore[no-redef]
            except ImportError as exc:
                raise AcadosUnavailable(f"acados_template import failed: {exc}") from exc
    _log_casadi_notice_instead(acados_template)
    return acados_template


def _log_casadi_notice_instead(template: ModuleType) -> None:
    """Replace the template's ``check_casadi_version`` with one that logs its notice once.

    The template prints (to stdout) a three-line "versions of CasADi are officially supported"
    notice each time it generates a solver, twice per solver: four times in a first
    ``reproduce`` with an empty cache. The notice is known and harmless here (code generation works
    with our CasADi; docs/planner.md); it stays available at INFO level (``--verbose``). Only that
    function is replaced; every other message of the template still prints.
    """
    from importlib.metadata import PackageNotFoundError, version

    try:
        casadi_version = version("casadi")
    except PackageNotFoundError:  # CasADi vendored by the acados wheel only
        casadi_version = "unknown"
    supported = getattr(sys.modules.get(f"{template.__name__}.utils"), "ALLOWED_CASADI_VERSIONS",
                        ())

    @functools.lru_cache(maxsize=1)
    def check_casadi_version() -> None:
        if casadi_version not in supported:
            _log.info("acados_template is tested with CasADi %s; this is CasADi %s",
                      " or ".join(supported), casadi_version)

    for name in ("utils", "acados_ocp_solver", "acados_sim_solver"):
        module = sys.modules.get(f"{template.__name__}.{name}")
        if module is not None and hasattr(module, "check_casadi_version"):
            module.check_casadi_version = check_casadi_version  # type: ignore[attr-defined]
