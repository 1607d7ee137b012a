"""Plain-Python learners the tests name as ``module:Class`` (importable by worker processes),
and how their runs are compared with the compiled method they port."""

# what may differ between a port's run and the compiled method's: its names, its clock
NAMING = ("key", "method", "method_name", "config", "wall_time_s", "wall_time_per_episode_s")


def differing(a: dict, b: dict) -> list[str]:
    """The fields of two runs' records that differ, naming and wall-clock fields aside."""
    return [k for k in a if k not in NAMING and a[k] != b.get(k)]
