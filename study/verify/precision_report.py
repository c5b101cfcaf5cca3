"""Reading a work-precision dataset (`study.verify.precision_study`): the cheapest run for a
target error, the text table and the log-log work-precision plot (PNG).
"""
from __future__ import annotations

import numpy as np
import xarray as xr


def time_of(ds: xr.Dataset) -> tuple[str, np.ndarray]:
    """('CPU' or 'wall', times [s]) a dataset's runs are compared by: the CPU time where the
    dataset holds it (a shared machine stretches the wall time), else the wall time."""
    return ("CPU", ds["cpu_time"].values) if "cpu_time" in ds else ("wall", ds["wall_time"].values)


def cheapest(ds: xr.Dataset, target_um: float, norm: str = "linf"):
    """(method, step [s] or rtol, time [s]) of the fastest ok run with error <= target_um
    [um] in ``norm``, by CPU time where the dataset holds it (`time_of`); None when no run
    reaches it."""
    e = ds["te_error"].sel(norm=norm).values
    w = time_of(ds)[1]
    ok = np.isfinite(e) & (e <= target_um) & np.isfinite(w)
    if not ok.any():
        return None
    i = int(np.flatnonzero(ok)[np.argmin(w[ok])])
    setting = ds["step"].values[i] if np.isfinite(ds["step"].values[i]) else ds["rtol"].values[i]
    return str(ds["method"].values[i]), float(setting), float(w[i])


def table(ds: xr.Dataset) -> str:
    """The study as a text table: method, step/tolerance, errors [um], CPU and wall time [s], status."""
    lines = [f"{ds.attrs['title']}: {ds.attrs['case']}",
             f"  reference: {ds.attrs['reference']}; cross-check: {ds.attrs['cross_check']}; "
             f"their difference (linf) {ds.attrs['reference_difference_linf_um']:.2g} um",
             f"  {'method':42s} {'step/rtol':>10s} {'final um':>10s} {'l2 um':>10s} {'linf um':>10s} {'cpu s':>9s} {'wall s':>9s}  status"]
    cpu = ds["cpu_time"].values if "cpu_time" in ds else np.full(ds.sizes["run"], np.nan)
    for i in range(ds.sizes["run"]):
        step = ds["step"].values[i]
        setting = f"{step * 1e6:.4g} us" if np.isfinite(step) else f"{ds['rtol'].values[i]:.0e}"
        e = ds["te_error"].values[i]
        st = ds["status"].values[i]
        msg = "" if st == "ok" else f"  {ds['message'].values[i]}"
        lines.append(f"  {ds['method'].values[i]:42s} {setting:>10s} {e[0]:10.3g} {e[1]:10.3g} {e[2]:10.3g} "
                     f"{cpu[i]:9.3g} {ds['wall_time'].values[i]:9.3g}  {st}{msg}")
    for target in (0.1, 0.01):
        c = cheapest(ds, target)
        lines.append(f"  cheapest for {target:g} um (linf): " + (f"{c[0]} at {setting_label(c[0], c[1])}, {c[2]:.3g} s "
                                                                 f"{time_of(ds)[0]}"
                                                                 if c else "none of the runs"))
    return "\n".join(lines)


def setting_label(method: str, setting: float) -> str:
    """'dt 0.312 us' for a fixed-step method, 'rtol 1e-06' for an adaptive one or the static solver."""
    fixed = method.startswith(("explicit", "implicit", "slow-ramp"))
    return f"dt {setting * 1e6:.4g} us" if fixed else f"rtol {setting:g}"


def plot(ds: xr.Dataset, path, norm: str = "linf") -> None:
    """Log-log work-precision diagram: TE error [um] against CPU time [s] (wall time for a
    dataset without it, `time_of`), one line per method, with a footer naming the machine, the
    versions and the reference."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 6))
    methods = list(dict.fromkeys(ds["method"].values))
    for m in methods:
        sel = (ds["method"].values == m)
        e = ds["te_error"].sel(norm=norm).values[sel]
        w = time_of(ds)[1][sel]
        ok = np.isfinite(e) & np.isfinite(w) & (e > 0)
        if ok.any():
            order = np.argsort(w[ok])
            ax.loglog(w[ok][order], e[ok][order], "o-", label=m)
    d = ds.attrs.get(f"reference_difference_{norm}_um", float("nan"))
    if np.isfinite(d) and d > 0:
        ax.axhline(d, color="k", ls=":", lw=1, label="reference vs cross-check")
    ax.set_xlabel(f"{time_of(ds)[0]} time of a run, compile excluded [s]")
    ax.set_ylabel(f"TE error, {norm} norm [um]")
    ax.set_title(ds.attrs.get("title", "work-precision"))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    save_with_footer(fig, ds, f"reference: {ds.attrs['reference']}; cross-check: {ds.attrs['cross_check']}", path)


def save_with_footer(fig, ds: xr.Dataset, reference: str, path, top: float = 1.0) -> None:
    """Write a study's figure (PNG, 120 dpi) with its footer: the case, ``reference`` (a line
    naming what the errors are measured against), the machine, the versions and the date;
    ``top``: the figure fraction the axes end at (room for a suptitle). Closes the figure."""
    import matplotlib.pyplot as plt
    footer = (f"{ds.attrs.get('case', '')}\n{reference}\n"
              f"{ds.attrs['machine']}; {ds.attrs.get('software', '')}; {ds.attrs['date']}")
    fig.text(0.01, 0.005, footer, fontsize=6, va="bottom", wrap=True)
    fig.tight_layout(rect=(0, 0.1, 1, top))
    fig.savefig(path, dpi=120)
    plt.close(fig)
