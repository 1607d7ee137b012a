"""Peak memory and checkpoint size per method and map size.

    python -m scenarios.bench.memory                          # rooms, 64..1024, five methods
    python -m scenarios.bench.memory --sizes 256 --methods rnh-ql+ --kind maze

Each measurement is one ``rnhql train MAP --method M --episodes E --save`` in a fresh
process, with the method's kernels compiled beforehand (compiling a kernel takes
up to ~300 MB for a few seconds, once per machine): the peak resident set size is the
kernel's ``ru_maxrss`` of that process (``os.wait4``), the checkpoint size the ``.npz``
on disk. A bare ``python -c "import learning, sim, scenarios.cli.app"`` is measured
too: the floor every run pays.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from scenarios.artifacts import write_artifact
from scenarios.script_args import arg, artifact_arg, parse
from scenarios.studies.maps.scaling_maps import write_problem

METHODS = ("rnh-ql+", "haql", "rnh-ql", "dyna-q", "st-ql")


PEAK_OF_CHILD = """
import atexit, os, sys
def _peak():  # this process's own high-water mark: VmHWM of the image exec built
    with open("/proc/self/status") as f:
        kb = next(int(line.split()[1]) for line in f if line.startswith("VmHWM:"))
    with open(os.environ["RNHQL_PEAK_FILE"], "w") as out:
        out.write(str(kb))
atexit.register(_peak)
flag, target, *rest = sys.argv[1:]  # -m MODULE ARGS... or -c CODE
sys.argv = [target, *rest]
if flag == "-m":
    import runpy
    runpy.run_module(target, run_name="__main__", alter_sys=True)
else:
    exec(target)
"""


def peak_rss_mb(cmd: list[str], env: dict[str, str]) -> tuple[float, int]:
    """(peak RSS [MB] of the process, exit status). Read inside the child (VmHWM, at its
    exit): the ``ru_maxrss`` that ``wait4`` gives counts, on Linux, the memory the child
    shared with this process when it was forked, so a parent that had built a 1024² map
    made every small run look as large as itself."""
    assert cmd[0] == sys.executable
    with tempfile.NamedTemporaryFile(prefix="rnhql-peak-", delete=False) as f:
        peak_file = Path(f.name)
    try:
        proc = subprocess.run([sys.executable, "-c", PEAK_OF_CHILD, *cmd[1:]],
                              env={**env, "RNHQL_PEAK_FILE": str(peak_file)},
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        if proc.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}): "
                               f"{proc.stderr.decode().strip()[-400:]}")
        return int(peak_file.read_text()) / 1024.0, proc.returncode
    finally:
        peak_file.unlink(missing_ok=True)


@dataclass(frozen=True)
class Args:
    sizes: str = arg("64,128,256,512,1024", "map sizes [cells a side]")
    kind: str = arg("rooms", "map kind (sim.maps.generators)")
    methods: str = arg(",".join(METHODS), "methods")
    episodes: int = arg(20, "training episodes per run")
    map_seed: int = arg(7, "generator seed of the maps")
    artifact: str | None = artifact_arg("memory")


def main(argv: list[str] | None = None) -> int:
    args = parse(Args, __doc__, argv)
    measured: dict[str, dict[str, list[float]]] = {}
    methods = [m for m in args.methods.split(",") if m]
    sizes = [int(s) for s in args.sizes.split(",")]
    with tempfile.TemporaryDirectory(prefix="rnhql-memory-") as tmp:
        folder = Path(tmp)
        env = dict(os.environ, NUMBA_CACHE_DIR=str(folder / "numba"))
        floor, _ = peak_rss_mb([sys.executable, "-c", "import learning, sim, scenarios.cli.app"],
                               env)
        print(f"floor (imports only): {floor:.0f} MB")
        print("| method | " + " | ".join(f"{n}²: peak RSS · checkpoint" for n in sizes) + " |")
        print("|---|" + "---|" * len(sizes))
        tomls = {n: write_problem(args.kind, n, args.map_seed, 0.1, folder / "maps")[0]
                 for n in sizes}
        for m in methods:  # compile first: the figures are the run's, not numba's
            peak_rss_mb([sys.executable, "-m", "scenarios.cli", "train", str(tomls[sizes[0]]),
                         "--method", m, "--episodes", "1"], env)
            cells = []
            for n in sizes:
                ckpt = folder / f"{m}-{n}.npz"
                rss, _ = peak_rss_mb([sys.executable, "-m", "scenarios.cli", "train",
                                      str(tomls[n]), "--method", m, "--episodes",
                                      str(args.episodes), "--save", str(ckpt)], env)
                size_mb = ckpt.stat().st_size / 1e6
                measured.setdefault(m, {})[str(n)] = [rss, size_mb]
                cells.append(f"{rss:.0f} MB · {size_mb:.1f} MB")
            print(f"| {m} | " + " | ".join(cells) + " |", flush=True)
    if args.artifact:
        cmd = ("python -m scenarios.bench.memory " + " ".join(argv if argv is not None
                                                               else sys.argv[1:]))
        write_artifact(f"memory.{args.artifact}", cmd.strip(), ["grid"],
                       {"kind": args.kind, "sizes": sizes, "episodes": args.episodes,
                        "floor_mb": floor, "methods": measured}, study=__file__)
    return 0


if __name__ == "__main__":
    sys.exit(main())
