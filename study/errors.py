"""The errors every input check raises (scene fields, study grids, options and paths), and the
argument checks of the Python API."""
from __future__ import annotations


class SceneError(ValueError):
    """Invalid scene input; ``field`` is the dotted path of the offending key."""

    def __init__(self, field: str, reason: str):
        self.field = field
        self.reason = reason
        super().__init__(f"{field}: {reason}")


class StudyError(SceneError):
    """Invalid study input (the base scene of a study, its grid, points or outputs); ``field``
    is the dotted scene field or the study key."""


class BudgetError(Exception):
    """A run refused before any work because its estimate exceeds the machine's memory or the
    time bound (``lightgear ... --max-time``); ``field`` names what to change."""

    def __init__(self, field: str, reason: str):
        self.field = field
        self.reason = reason
        super().__init__(f"{field}: {reason}")


class UsageError(Exception):
    """Bad command-line input (an option, an output path, an archive): exit 2."""

    def __init__(self, option: str, reason: str):
        super().__init__(f"{option}: {reason}")


# ---------------------------------------------------------------- argument checks of the Python API
# A function of the API (`study`) given a wrong type raises TypeError at once, naming itself,
# the argument and what it takes; each function checks its own arguments where it is written.

def check_argument(ok: bool, function: str, argument: str, takes: str, value) -> None:
    """TypeError naming the function, the argument and what it takes, when not ``ok``."""
    if not ok:
        raise TypeError(f"{function}: {argument} takes {takes}, got {type(value).__name__} {value!r:.80}")


def check_scene_argument(function: str, scene) -> None:
    """TypeError naming ``function`` unless ``scene`` is a `study.scene.Scene` (known here by its
    class's module and name: the errors sit below the scene and import nothing of the project)."""
    kind = type(scene)
    check_argument(kind.__module__ == "study.scene" and kind.__name__ == "Scene", function, "scene",
                   "a Scene (study.load_scene(path or name), study.default_scene(), Scene.replace(...))", scene)


def is_path(x) -> bool:
    """A file path as the API takes it: str or os.PathLike."""
    import os
    return isinstance(x, str | os.PathLike)


def is_number(x) -> bool:
    """A real number, NumPy's included, not a bool."""
    import numbers
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


def checked_workers(function: str, workers) -> int | None:
    """``workers`` as an int >= 0, or None (one per core); TypeError for another type, ValueError below 0."""
    import numbers
    check_argument(workers is None or (isinstance(workers, numbers.Integral) and not isinstance(workers, bool)),
                   function, "workers", "an integer >= 0 (0: in this process) or None (one per core)", workers)
    if workers is not None and workers < 0:
        raise ValueError(f"{function}: workers takes an integer >= 0 (0: in this process) or None (one per core), "
                         f"got {workers}")
    return None if workers is None else int(workers)
