"""What ``reform-sim twin`` does when it runs.

Its arguments are `sim.cli._twin`."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from sim.cli._common import check_output, job_count, load_data
from sim.cli._grammar import ticking_bar
from sim.twins import check_frames_for_twin, fit_twin, twin_sample, write_twin
from sim.twins.description import Fitted

TWIN_JSON = "twin.json"
TWIN_PNG = "twin.png"


def _run(args: argparse.Namespace) -> int:
    check_output("--out", args.out, folder=True)
    dataset = load_data(args)
    frames = list(dataset)
    check_frames_for_twin(frames, where=args.data)
    name = dataset.name or Path(args.data).name
    with ticking_bar(args, f"fitting a twin of {name}", len(frames)):  # seconds to a minute
        twin = fit_twin(
            frames,
            name=name,
            seed=args.seed,
            use_labels=args.use_labels,
            where=args.data,
            n_jobs=job_count(args),
        )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    written = [write_twin(twin, out / TWIN_JSON)]
    if not args.no_plots:
        from sim.twins.plots import plot_twin

        with ticking_bar(args, f"plotting {TWIN_PNG}", 1, unit="plot"):
            written.append(plot_twin(twin, frames, twin_sample(twin), out / TWIN_PNG))
    print(_fitted_table(twin.fitted))
    print(f"wrote {', '.join(str(p) for p in written)} ({twin.mode})")
    return 0


def _fitted_table(rows: Sequence[Fitted]) -> str:
    """One line per fitted value: the value, the statistic that fixed it and its real and twin
    figures. Values searched together on one statistic (the crowd's shape: a list of figures)
    name it by a letter, and it is written out once below them with its two lists."""
    lines, shared = [], {}
    for fitted in rows:
        if fitted.name.startswith("("):
            continue
        value = f"{fitted.value:.6g}" if isinstance(fitted.value, float) else str(fitted.value)
        if isinstance(fitted.real, list):
            key = (fitted.statistic, tuple(fitted.real), tuple(fitted.twin or ()))
            mark = shared.setdefault(key, f"[{chr(ord('a') + len(shared))}]")
            lines.append(f"{fitted.name:28} {value:>10}  searched on statistic {mark}")
            continue
        beside = "" if fitted.real is None else f"  (real {fitted.real}, twin {fitted.twin})"
        lines.append(f"{fitted.name:28} {value:>10}  {fitted.statistic}{beside}")
    for (statistic, real, twin), mark in shared.items():
        lines += [f"{mark} {statistic}:", f"    real {list(real)}", f"    twin {list(twin)}"]
    return "\n".join(lines)
