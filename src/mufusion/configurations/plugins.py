"""Plug-ins: a friction source, planner or controller named by import path or entry point.

A plug-in is named in the CLI (``mufusion run popup --config mypkg.estimators:SlipRLS``) and in
campaign files (``configs = ["GT", "F", "mypkg.estimators:SlipRLS"]``) by

* an import path ``module:attribute`` (the attribute may be dotted), or
* the name of an entry point of an installed package, in the group :data:`FRICTION_SOURCES`
  (``mufusion.friction_sources``), :data:`PLANNERS` or :data:`CONTROLLERS`; e.g. in its
  ``pyproject.toml``: ``[project.entry-points."mufusion.friction_sources"] slip-rls =
  "mypkg.estimators:SlipRLS"``.

The attribute is a factory (a class, a function) or the component itself: a friction source's
factory is called without arguments, once per run, so that each run starts from a fresh state (a
component given as an object is shared by every run of the process). The name is
the run's label in logs, tables and figures; it may not be a built-in configuration's name. Modules
are imported the way ``python -m`` does: with the current directory on the import path
(:func:`import_from_cwd`); the campaign's process pool inherits it, a Ray cluster does not (there
the plug-in must be installed, or on the workers' ``PYTHONPATH``).

Errors (the module does not import, the attribute is missing, the factory raises, the result
lacks the calls of its protocol) are :class:`PluginError`, a :class:`ValueError` naming the
plug-in, raised by :func:`check_friction_spec` before any run.
"""

from __future__ import annotations

import importlib
import inspect
import os
import sys
from collections.abc import Callable
from importlib.metadata import entry_points
from typing import Any

from mufusion.configurations.interface import channels_of
from mufusion.configurations.registry import CONFIGURATION_NAMES, Configuration
from mufusion.estimators.sensors import Channel

FRICTION_SOURCES = "mufusion.friction_sources"
"""Entry-point group of installed friction sources."""
PLANNERS = "mufusion.planners"
"""Entry-point group of installed planners (called ``factory(params, planner_config)``)."""
CONTROLLERS = "mufusion.controllers"
"""Entry-point group of installed controllers (called ``factory(params, planner_config)``)."""


class PluginError(ValueError):
    """A plug-in that cannot be used; the message names it and says why."""


def import_from_cwd() -> None:
    """Put the current directory on the import path, as ``python -m`` does (idempotent).

    Worker processes started by ``multiprocessing`` inherit the import path, so a plug-in
    module next to a campaign file imports in every run.
    """
    cwd = os.getcwd()
    if cwd not in sys.path and "" not in sys.path:
        sys.path.insert(0, cwd)


def is_builtin(spec: object) -> bool:
    """Whether ``spec`` names one of the built-in configurations (GT, L, P, F, F-safe)."""
    return isinstance(spec, Configuration) or (
        isinstance(spec, str) and spec in CONFIGURATION_NAMES
    )


def load_plugin(spec: str, group: str) -> Any:
    """The object ``spec`` names: ``module:attribute``, or an entry point's name in ``group``.

    Raises
    ------
    PluginError
        If ``spec`` names nothing (the message says what was tried), the module fails to import
        or lacks the attribute.
    """
    if not isinstance(spec, str) or not spec.strip():
        raise PluginError(
            f"plug-in name must be 'module:attribute' or an entry point, got {spec!r}"
        )
    if ":" not in spec:
        found = [ep for ep in entry_points(group=group) if ep.name == spec]
        if not found:
            raise PluginError(
                f"{spec!r} is neither a built-in configuration ({', '.join(CONFIGURATION_NAMES)}),"
                f" an import path 'module:attribute', nor an entry point in group {group!r}"
            )
        try:
            return found[0].load()
        except Exception as exc:
            raise PluginError(f"plug-in {spec!r} (entry point {found[0].value!r}) failed to load: "
                              f"{type(exc).__name__}: {exc}") from exc
    module_name, _, attribute = spec.partition(":")
    try:
        obj: Any = importlib.import_module(module_name)
    except Exception as exc:
        raise PluginError(f"plug-in {spec!r}: module {module_name!r} failed to import: "
                          f"{type(exc).__name__}: {exc}") from exc
    for part in attribute.split("."):
        if not hasattr(obj, part):
            raise PluginError(f"plug-in {spec!r}: {module_name!r} has no attribute {attribute!r}")
        obj = getattr(obj, part)
    return obj


def _instantiate(spec: str, obj: Any, *args: Any) -> Any:
    if not (inspect.isclass(obj) or inspect.isfunction(obj)):
        return obj  # the component itself
    try:
        return obj(*args)
    except Exception as exc:
        raise PluginError(
            f"plug-in {spec!r}: making it failed: {type(exc).__name__}: {exc}"
        ) from exc


def _require(spec: str, obj: Any, what: str, calls: tuple[str, ...]) -> None:
    missing = [c for c in calls if not callable(getattr(obj, c, None))]
    if missing:
        name = obj.__name__ if inspect.isclass(obj) else type(obj).__name__
        raise PluginError(f"plug-in {spec!r} is not a {what}: {name} has no "
                          f"callable {', '.join(missing)}")


def make_friction_plugin(spec: str) -> Any:
    """A fresh friction source from the plug-in ``spec`` (see the module docstring).

    Raises
    ------
    PluginError
        If it cannot be loaded or made, its ``step`` (or ``observe``, when present) is not
        callable with a frame (with the truth too, if it declares ``Channel.TRUTH``), or its
        ``channels`` are not :class:`~mufusion.estimators.sensors.Channel` names.
    """
    if is_builtin(spec):
        raise PluginError(f"{spec!r} is a built-in configuration, not a plug-in")
    source = _instantiate(spec, load_plugin(spec, FRICTION_SOURCES))
    _require(spec, source, "friction source", ("step",))
    try:
        channels = channels_of(source)
    except ValueError as exc:
        raise PluginError(f"plug-in {spec!r}: {exc}") from None
    _check_arity(spec, source.step, 2 if Channel.TRUTH in channels else 1, "step")
    observe = getattr(source, "observe", None)
    if observe is not None:
        _check_arity(spec, observe, 1, "observe")
    return source


def _check_arity(spec: str, call: Callable[..., Any], n: int, what: str) -> None:
    try:
        inspect.signature(call).bind(*([None] * n))
    except TypeError:
        names = "frame, truth" if n == 2 else "frame" if what == "step" else "signals"
        raise PluginError(
            f"plug-in {spec!r}: {what} must accept {n} positional argument(s) ({names})"
        ) from None
    except ValueError:  # no signature to inspect (a builtin): trust it
        return


def check_friction_spec(spec: str) -> str:
    """Check a configuration name before any run: a built-in one, or a usable plug-in.

    Returns
    -------
    str
        ``spec`` itself (the run's label).

    Raises
    ------
    PluginError
        As :func:`make_friction_plugin`, naming the plug-in.
    """
    if is_builtin(spec):
        return str(spec)
    import_from_cwd()
    make_friction_plugin(spec)
    return spec


_PROTOCOLS: dict[str, tuple[str, tuple[str, ...]]] = {
    PLANNERS: ("planner", ("step", "restore")),
    CONTROLLERS: ("controller", ("command",)),
}


def check_component_spec(spec: str, group: str) -> str:
    """Check a planner (``group=PLANNERS``) or controller (``CONTROLLERS``) plug-in before any
    run: it loads, and a class or object has the calls of its protocol (a factory function is
    checked when called, at the start of a run).

    Returns
    -------
    str
        ``spec`` itself.

    Raises
    ------
    PluginError
        Naming the plug-in, as :func:`load_plugin`, or if a call is missing.
    """
    import_from_cwd()
    obj = load_plugin(spec, group)
    if not inspect.isfunction(obj):
        what, calls = _PROTOCOLS[group]
        _require(spec, obj, what, calls)
    return spec


def make_component_plugin(spec: str, group: str, *args: Any) -> Any:
    """A planner (``group=PLANNERS``) or controller (``CONTROLLERS``) from the plug-in ``spec``,
    its factory called with ``args`` (the vehicle's parameters and the planner's configuration).

    Raises
    ------
    PluginError
        If it cannot be loaded or made, or lacks a call of its protocol (a planner: ``step``,
        ``restore``; a controller: ``command``).
    """
    check_component_spec(spec, group)  # a class lacking a call is refused before it is made
    component = _instantiate(spec, load_plugin(spec, group), *args)
    _require(spec, component, *_PROTOCOLS[group])
    return component


def check_plugins(
    *, config: str | None = None, planner: str | None = None, controller: str | None = None
) -> None:
    """Check the friction source, planner and controller a command names, before any run.

    Raises
    ------
    PluginError
        Prefixed with the option that names the unusable plug-in (``--config``, ``--planner``,
        ``--controller``).
    """
    checks = [("--config", config, check_friction_spec),
              ("--planner", planner, lambda s: check_component_spec(s, PLANNERS)),
              ("--controller", controller, lambda s: check_component_spec(s, CONTROLLERS))]
    for option, spec, check in checks:
        if spec is not None:
            try:
                check(spec)
            except PluginError as err:
                raise PluginError(f"{option}: {err}") from None
