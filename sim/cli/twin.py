"""What ``reform-sim twin`` does when it runs.

Its arguments are `sim.cli._twin`."""

from __future__ import annotations

import argparse
from pathlib import Path

from sim.cli._common import check_output, load_data
from sim.cli._grammar import ticking_bar
from sim.twins import check_frames_for_twin, fit_twin, twin_sample, write_twin

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
            frames, name=name, seed=args.seed, use_labels=args.use_labels, where=args.data
        )
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    written = [write_twin(twin, out / TWIN_JSON)]
    if not args.no_plots:
        from sim.twins.plots import plot_twin

        with ticking_bar(args, f"plotting {TWIN_PNG}", 1, unit="plot"):
            written.append(plot_twin(twin, frames, twin_sample(twin), out / TWIN_PNG))
    for fitted in twin.fitted:
        if fitted.name.startswith("("):
            continue
        beside = "" if fitted.real is None else f"  (real {fitted.real}, twin {fitted.twin})"
        print(f"{fitted.name:28} {fitted.value!s:>10}  {fitted.statistic}{beside}")
    print(f"wrote {', '.join(str(p) for p in written)} ({twin.mode})")
    return 0
