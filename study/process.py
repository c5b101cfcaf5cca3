"""How a command or a script ends as a process: the errors a user can meet as one line on
stderr and the exit codes of `lightgear --help` (`study.cli.EXIT_CODES`: 2 invalid input or a
run refused by its estimate, 130 interrupted by Ctrl-C or SIGTERM, 1 anything else), no traceback.

The command line (`study.cli`) and the workflow scripts (`study.script_main`) both end here."""
from __future__ import annotations

import sys

from study.errors import UsageError


def stop_on_sigterm():
    """SIGTERM handled as Ctrl-C (KeyboardInterrupt: the running kernel stops, exit 130) while
    a command runs; a context manager that restores the previous handler. Outside the main
    thread (no signal handlers there) it does nothing."""
    import contextlib
    import signal
    import threading

    def interrupt(signum, frame):
        raise KeyboardInterrupt(f"signal {signum}")

    @contextlib.contextmanager
    def handler():
        if threading.current_thread() is not threading.main_thread():
            yield
            return
        old = signal.signal(signal.SIGTERM, interrupt)
        try:
            yield
        finally:
            signal.signal(signal.SIGTERM, old)
    return handler()


def end_of_process() -> None:
    """The process ends now: spare it the final collection of every object (1-2 s after a
    run), so that an interrupted command is gone at once."""
    import gc
    gc.freeze()


def guarded(name: str, command) -> int:
    """``command()``'s exit code, with the errors a user can meet turned into the exit codes of
    `study.cli.EXIT_CODES` and one line on stderr that starts with ``name``."""
    import os
    import warnings

    from solver.geometry import GeometryError
    from study.errors import BudgetError, StudyError
    from study.scene import SceneError

    def one_line(message, category, filename, lineno, file=None, line=None):
        # a library's warning as one line that says who speaks, not its source line
        print(f"{name}: warning: {category.__name__}: {str(message).splitlines()[0] if str(message) else ''}",
              file=sys.stderr)
    shown = warnings.showwarning
    warnings.showwarning = one_line
    try:
        return int(command() or 0)
    except (SceneError, GeometryError) as e:
        what = "study" if isinstance(e, StudyError) else "scene"
        print(f"{name}: invalid {what}: {e}", file=sys.stderr)
        return 2
    except UsageError as e:
        print(f"{name}: {e}", file=sys.stderr)
        return 2
    except BudgetError as e:
        print(f"{name}: refused before any work: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"{name}: interrupted", file=sys.stderr)
        return 130
    except Exception as e:  # noqa: BLE001 - the backstop: one line, no traceback unless asked
        if os.environ.get("LIGHTGEAR_DEBUG", "") not in ("", "0"):
            raise
        first = str(e).splitlines()[0] if str(e) else ""
        print(f"{name}: error: {type(e).__name__}: {first} (LIGHTGEAR_DEBUG=1 shows the traceback)", file=sys.stderr)
        return 1
    finally:
        warnings.showwarning = shown


def script_main(name: str, main_function) -> int:
    """Exit code of a workflow script's ``main_function()`` run as a program (``python -m
    workflows.NAME``): the command line's exit codes, SIGTERM as Ctrl-C, one line per error."""
    with stop_on_sigterm():
        code = guarded(name, main_function)
    end_of_process()
    return code
