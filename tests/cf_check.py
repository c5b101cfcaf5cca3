"""The IOOS compliance checker's CF-1.8 errors (its high-priority failures) on a NetCDF file."""

# The checker asks every dimension named `time` to be a calendar axis (§5.1: standard_name
# 'time', hence units '<unit> since <epoch>'). The archives' `time` is the elapsed time of a
# simulated run in s, which CF leaves without a standard name; made a calendar axis, xarray
# would decode it into dates. That one check is skipped, and only that one.
SKIPPED = ("check_spatiotemporal_dims_have_coordinate_vars",)


def cf_errors(path) -> list[str]:
    """'section: message' for each failed high-priority CF-1.8 check of the file at ``path``."""
    from compliance_checker.base import BaseCheck
    from compliance_checker.runner import CheckSuite
    suite = CheckSuite()
    suite.load_all_available_checkers()
    ds = suite.load_dataset(str(path))
    try:
        groups, _checker_exceptions = suite.run_all(ds, ["cf:1.8"], skip_checks=list(SKIPPED))["cf:1.8"]
    finally:
        ds.close()
    out = []
    for r in groups:
        passed = r.value if isinstance(r.value, bool) else r.value[0] >= r.value[1]
        if r.weight == BaseCheck.HIGH and not passed:
            out += [f"{r.name}: {m}" for m in r.msgs] or [str(r.name)]
    return out
