"""The machine's memory as a run sees it: what is available now [bytes], and a size in words.

Below every module that refuses a run before its arrays are built (`study.scene_model`'s static
angles, `study.estimate`'s outputs and study sizes)."""
from __future__ import annotations

import math
import os


def bytes_text(b: float) -> str:
    """A size [bytes] in words: '1.5 GiB'."""
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20)):
        if b >= size:
            return f"{b / size:.3g} {unit}"
    return f"{b / 1024:.3g} KiB"


def available_memory() -> float:
    """Memory the machine can give a run now [bytes]: MemAvailable of /proc/meminfo, else the
    physical memory."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return math.inf
