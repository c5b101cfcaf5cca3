"""The error every input check raises: scene fields, study grids, options and paths."""
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
