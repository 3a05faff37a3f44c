"""The catalogue: every detector the project ships, by name, with its options and citation.

One entry per detector configuration (`reform.detectors.register_detector`'s table), each with
one name, one factory (imported only when the detector is made, so that listing the catalogue
stays light), its options declared once as `reform.detectors.Option` (type, default, range,
unit, help) and the paper it implements. The command line (``--detector``, ``--option``,
``--help``), the benchmarks, the stress tests, the studies and the Gymnasium environments read
the catalogue; no other module keeps a list of detectors.

Adding a built-in detector is one module with its estimator and one ``_register`` call here.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from typing import TYPE_CHECKING

from reform.detectors import Option, _register

if TYPE_CHECKING:
    from reform.detector import Reform
    from reform.gcff import Gcff

__all__: list[str] = []

# GCFF's "one stated setting": the REFORM paper's stride 0.7 (70 cm) and MDL 30000 (cm²).
GCFF_STRIDE_M = 0.7  # metres
GCFF_MDL_M2 = 3.0  # square metres
_GCFF_STRIDE_GRID_M = (0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)  # metres, as reform.gcff.STRIDE_GRID_M
_GCFF_MDL_GRID_M2 = (
    0.5,
    0.75,
    1.0,
    1.5,
    2.0,
    3.0,
    4.0,
)  # square metres, as reform.gcff.MDL_GRID_M2

GCFF_CITATION = (
    "Setti, Russell, Bassetti, Cristani. F-formation detection: individuating free-standing "
    "conversational groups in images. PLoS ONE 10(5), 2015"
)
REFORM_CITATION = (
    "Hedayati, Muehlbradt, Szafir, Andrist. REFORM: Recognizing F-formations for Social "
    "Robots. IROS 2020"
)

_ORIENTATION = Option(
    "orientation",
    "str",
    "body",
    "the orientation each person's o-space vote follows",
    choices=("body", "head"),
)


def _reform(*, model: str | os.PathLike[str], trusted: Iterable[str] = ()) -> Reform:
    """REFORM from a model file written by `reform-sim train` (`reform.persistence.load_model`)."""
    # Imported here: scikit-learn and skops load only when a REFORM model is made.
    from reform.persistence import load_model

    return load_model(model, trusted=trusted)


_register(
    "majority",
    "reform.majority:Majority",
    help="majority baseline: everyone alone, every pair 'not together'",
    source="built-in",
)
_register(
    "gcff",
    "reform.gcff:Gcff",
    help="GCFF graph-cut baseline (Setti et al. 2015); options stride (m), mdl (m²), orientation",
    source="built-in",
    options=(
        Option(
            "stride",
            "float",
            GCFF_STRIDE_M,
            "distance of the o-space centre each person votes for, in front of them",
            unit="m",
            low=0.01,
            high=10.0,
            grid=_GCFF_STRIDE_GRID_M,
        ),
        Option(
            "mdl",
            "float",
            GCFF_MDL_M2,
            "cost of opening one more group (the paper's MDL 30000 cm² = 3.0 m²)",
            unit="m²",
            low=1e-6,
            high=1e4,
            grid=_GCFF_MDL_GRID_M2,
        ),
        _ORIENTATION,
    ),
    citation=GCFF_CITATION,
)
_register(
    "gcff-own",
    "reform.gcff:GcffOwn",
    help="GCFF with the settings each dataset ships (settings_gc.mat, per sequence)",
    source="built-in",
    options=(_ORIENTATION,),
    citation=GCFF_CITATION,
    needs="dataset",
)


def _gcff_tuned(*, orientation: str = "body", objective: str = "2/3") -> Gcff:
    """GCFF whose stride and mdl are grid-searched on annotated training frames by ``fit``."""
    from reform.gcff import Gcff

    return Gcff(
        tune=True,
        orientation=orientation,
        stride_grid=_GCFF_STRIDE_GRID_M,
        mdl_grid=_GCFF_MDL_GRID_M2,
        threshold=objective,
    )


_register(
    "gcff-tuned",
    _gcff_tuned,
    help="GCFF with stride and mdl searched on annotated training frames (F1 at the objective T)",
    source="built-in",
    options=(
        _ORIENTATION,
        Option(
            "objective",
            "str",
            "2/3",
            "the threshold T whose F1 the search maximises",
            choices=("2/3", "1"),
        ),
    ),
    citation=GCFF_CITATION,
    needs="training",
)
_register(
    "reform",
    _reform,
    help="REFORM (Hedayati et al. 2020) from a model file: option model (`reform-sim train`)",
    source="built-in",
    options=(Option("model", "path", None, "a model file written by `reform-sim train` (.skops)"),),
    citation=REFORM_CITATION,
)

DANTE_CITATION = (
    "Swofford, Peruzzi, Tsoi, Thompson, Martín-Martín, Savarese, Vázquez. Improving Social "
    "Awareness Through DANTE: Deep Affinity Network for Clustering Conversational "
    "Interactants. CSCW 2020"
)
_register(
    "dante",
    "reform.dante:make_dante",
    help="DANTE (Swofford et al. 2020) from a model file (option model, `reform-sim train "
    "--detector dante`), or untrained to fit; needs the extra reform-sim[dante]",
    source="built-in",
    options=(
        Option(
            "model",
            "path",
            None,
            "a model file written by `reform-sim train --detector dante` (.safetensors); "
            "without it the detector is untrained and must be fitted",
        ),
        Option(
            "orientation",
            "str",
            "body",
            "the orientation each person carries (both: body and head, DANTE's SALSA input)",
            choices=("body", "head", "both"),
        ),
        Option("epochs", "int", 600, "most passes over the training pairs", low=1, high=100_000),
        Option(
            "learning_rate", "float", 1e-4, "Adam's step size while training", low=1e-7, high=1.0
        ),
        Option("batch_size", "int", 1024, "pairs per gradient step", low=2, high=1 << 20),
        Option(
            "random_state",
            "int",
            0,
            "seeds the weights, the shuffling and dropout: one seed, one model",
            low=0,
            high=2**32 - 1,
        ),
    ),
    citation=DANTE_CITATION,
)
