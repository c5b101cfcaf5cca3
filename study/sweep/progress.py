"""One progress bar for a study: its FE bodies and its points together, with an estimated time
to the end from the start (not '?' until the first point ends).

The bar counts points (a point is done when all its analyses are) and says how many FE bodies
and analyses are done. Its ETA is the estimated work left (`study.sweep.cost.progress_seconds` per
analysis, `study.estimate.body_seconds` per FE body), divided among the workers, and, once
analyses have ended, calibrated by what they took: the median over the ended analyses of their
measured time over their estimate, leaving out each worker's first (which also loads or
compiles the kernels and builds a model: the median, so that no single slow analysis sets the
pace of the rest). Until each worker's first analysis has ended, the start of the workers and a
kernel compile still to come are counted too.
"""
from __future__ import annotations

import math
import statistics
import sys
import time

START_S = 3.0          # workers up and the first imports [s]
COMPILE_S = 13.0       # the kernels compiled once on a machine whose numba cache lacks them [s of CPU]


class StudyProgress:
    """The bar of one study run. ``fe_costs``: {FE job key: estimated s}; ``task_costs``:
    {analysis key: estimated s}; ``parallel``: workers computing at once; ``startup_s``: what
    comes before the first analysis ends besides the FE and the analyses (workers, compile)."""

    def __init__(self, title: str, points: int, fe_costs: dict, task_costs: dict, parallel: int,
                 startup_s: float = 0.0, show: bool = True, fe_in_tasks: dict | None = None):
        from tqdm import tqdm
        self.fe_left = dict(fe_costs)
        self.fe_total = len(fe_costs)
        task_costs = dict(task_costs)
        # ``fe_in_tasks`` ({analysis key: FE job keys}): the FE runs inside the analyses that
        # first read it (in process): its cost is theirs, and it is done when they are
        self.fe_in_tasks = fe_in_tasks
        for key, jobs in (fe_in_tasks or {}).items():
            task_costs[key] = task_costs.get(key, 0.0) + sum(fe_costs.get(j, 0.0) for j in jobs)
        self.tasks_left = task_costs
        self.tasks_total = len(task_costs)
        self.parallel = max(1, int(parallel))
        self.startup_s = float(startup_s)
        self.ratios: list[float] = []
        self.t0 = time.perf_counter()
        self.first_eta = None
        self.bar = tqdm(total=points, desc=title[:40], unit="point", disable=not show, file=sys.stderr,
                        bar_format="{desc}: |{bar}| {n_fmt}/{total_fmt} points{postfix} [{elapsed}]")
        self._show()

    def eta_s(self) -> float:
        """Seconds to the end of the study as now estimated."""
        from study.estimate import load_factor
        # each worker's first analysis also loads (or compiles) the kernels and builds a model:
        # the pace comes from the analyses after those, the estimate's own until then
        later = self.ratios[self.parallel:]
        pace = statistics.median(later) if later else 1.0
        fe = 0.0 if self.fe_in_tasks is not None else sum(self.fe_left.values())
        work = (fe + sum(self.tasks_left.values())) * pace
        left = work / min(self.parallel, max(1, len(self.tasks_left) + len(self.fe_left)))
        if len(self.ratios) < self.parallel:
            left += self.startup_s * load_factor() * (1 - len(self.ratios) / self.parallel)
        return max(0.0, left)

    def _show(self) -> None:
        eta = self.eta_s()
        if self.first_eta is None:
            self.first_eta = eta
        parts = []
        if self.fe_total:
            parts.append(f"FE bodies {self.fe_total - len(self.fe_left)}/{self.fe_total}")
        parts.append(f"analyses {self.tasks_total - len(self.tasks_left)}/{self.tasks_total}")
        parts.append(f"ETA {eta_text(eta)}")
        self.bar.set_postfix_str(", ".join(parts), refresh=True)

    def fe_done(self, key: str) -> None:
        self.fe_left.pop(key, None)
        self._show()

    def task_done(self, key: str, wall_time: float | None, points_finished: int) -> None:
        est = self.tasks_left.pop(key, None)
        for job in (self.fe_in_tasks or {}).get(key, ()):
            self.fe_left.pop(job, None)
        if est and wall_time is not None and math.isfinite(wall_time) and wall_time > 0:
            self.ratios.append(wall_time / est)
        if points_finished:
            self.bar.update(points_finished)
        self._show()

    def close(self) -> None:
        self.bar.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def eta_text(s: float) -> str:
    """'25 s', '3 min 10 s', '1 h 05 min'."""
    s = int(round(s))
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {s % 3600 // 60:02d} min"
