"""The one store of computed results a process keeps in memory: named shelves, each holding the
last ``slots`` results of one kind by a key of their content, one key rule (`digest`) and one
`Store.clear` for everything.

A result is kept by a digest of everything it depends on (the arrays it reads, the settings it
was made with), never by who asked first, so a kept result is the result its key would make
again: what is kept changes how long a run takes, never a bit of what it gives. Each shelf is
bounded: the least recently used result goes first, before a new one is made (a factorised FE
body holds hundreds of MB). The solver's model-only analyses, the loaded equilibria, the
study's models, FE maps, bodies, rims and coupling fits all live on shelves of `STORE`.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
from collections import OrderedDict

import numpy as np


def digest(*parts) -> str:
    """32 hex digits (BLAKE2b) of ``parts``: arrays (and NumPy numbers) by dtype, shape and bytes,
    anything else by its JSON (sorted keys; arrays inside in full, dataclasses by their fields,
    other values JSON does not take by their ``repr``)."""
    h = hashlib.blake2b(digest_size=16)
    for p in parts:
        if isinstance(p, np.ndarray | np.generic):
            a = np.ascontiguousarray(p)
            h.update(f"{a.dtype.str}{a.shape}".encode())
            h.update(a.tobytes())
        else:
            h.update(json.dumps(p, sort_keys=True, default=_plain).encode())
        h.update(b"|")
    return h.hexdigest()


def _plain(value):
    """A value JSON does not take, in full: arrays as lists (not NumPy's shortened repr),
    dataclasses as their fields, anything else by its repr."""
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {"__class__": type(value).__name__, **{f.name: getattr(value, f.name) for f in dataclasses.fields(value)}}
    return repr(value)


class Shelf(OrderedDict):
    """The last ``slots`` results of one kind, by key (least recently used first)."""

    def __init__(self, name: str, slots: int):
        super().__init__()
        if slots < 1:
            raise ValueError(f"shelf {name!r}: slots must be >= 1, got {slots}")
        self.name = name
        self.slots = slots

    def kept(self, key, make):
        """The result of ``key``, made by ``make()`` when not held; the least recently used
        results go first, before it is made, so that at most ``slots`` are held. An exception
        of ``make`` keeps nothing."""
        if key in self:
            self.move_to_end(key)
            return self[key]
        while len(self) >= self.slots:
            self.popitem(last=False)
        value = make()
        self[key] = value
        return value

    def __setitem__(self, key, value):
        super().__setitem__(key, value)
        while len(self) > self.slots:
            self.popitem(last=False)

    def __reduce__(self):       # a shelf goes to another process empty: results are not sent along
        return (Shelf, (self.name, self.slots))


class Store:
    """Every shelf of the process, by name; `clear` empties them all."""

    def __init__(self):
        self.shelves: dict[str, Shelf] = {}

    def shelf(self, name: str, slots: int) -> Shelf:
        """The shelf ``name`` holding at most ``slots`` results (made on first use)."""
        shelf = self.shelves.get(name)
        if shelf is None:
            shelf = self.shelves[name] = Shelf(name, slots)
        elif shelf.slots != slots:
            raise ValueError(f"shelf {name!r} holds {shelf.slots} results, asked again with {slots}")
        return shelf

    def clear(self) -> None:
        """Forget every result held in memory (disk caches stay)."""
        for shelf in self.shelves.values():
            shelf.clear()

    def sizes(self) -> dict[str, int]:
        """Results held per shelf."""
        return {name: len(shelf) for name, shelf in self.shelves.items()}


STORE = Store()
