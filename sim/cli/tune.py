"""What ``reform-sim tune`` does when it runs.

Its arguments are `sim.cli._tune`."""

from __future__ import annotations

import argparse
import shlex
from pathlib import Path

from sim.cli._common import CliError, check_output, job_count, twin_data_name
from sim.cli._grammar import ticking_bar


def _run(args: argparse.Namespace) -> int:
    from sim.generate import FolderRefused
    from sim.twins import read_twin, twin_data
    from sim.twins.data import DATA_FOLDER
    from sim.twins.tune import REFORM, check_tunable, tune_detector, write_tuned

    twin = read_twin(args.twin)  # a nonsense twin or detector is one line, before any work
    name = check_tunable(args.detector)
    suffix = ".skops" if name == REFORM else ".json"
    out = Path(args.out) if args.out else Path(args.twin).parent / f"tuned-{name}{suffix}"
    check_output("--out", out, suffix=suffix)
    folder = Path(args.twin_data) if args.twin_data else Path(args.twin).parent / DATA_FOLDER
    try:
        frames = list(twin_data(twin, folder, n_jobs=args.jobs, progress=not args.quiet))
    except FolderRefused as exc:  # named as the command names it
        raise CliError(exc.message(twin_data_name(args))) from None
    # Every setting scored on the twin's frames, on --jobs processes (gcff's 49: seconds).
    with ticking_bar(args, f"tuning {name} on the twin", len(frames)):
        tuned = tune_detector(name, frames, n_jobs=job_count(args))
    if name == REFORM:
        from reform.persistence import save_model

        save_model(tuned.model, out)
        use = f"--detector reform --model {shlex.quote(str(out))}"
    else:
        chosen_on = {"twin": str(args.twin), "twin_data": str(folder), "labels read": "none"}
        write_tuned(out, tuned, chosen_on=chosen_on)
        use = f"--detector {name} --settings {shlex.quote(str(out))}"
    if name == REFORM:
        best = max(tuned.grid, key=lambda row: row["f1"])
        chosen = f"REFORM {best['options']['classifier']}"
    else:
        chosen = ", ".join(f"{k}={v}" for k, v in tuned.options.items())
    print(
        f"{name} on the twin of {twin.name}: {chosen} (F1 at T=2/3 on the twin "
        f"{100 * tuned.f1:.1f}, {len(tuned.grid)} settings, {tuned.frames} frames); wrote {out}"
    )
    print(f"use: reform-sim detect {use} --data DATASET --out groups.json")
    return 0
