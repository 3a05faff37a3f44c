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
            lean="low",  # a cheaper group: neighbours are merged less
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


# REFORM fitted where it runs: the training frames `reform.prepare_detector` gives (benchmark:
# each dataset's training part; evaluate: --tune-on), with the options beyond the paper
# (docs/guide/reform-options.md) as named configurations. The choices are literals so that the
# catalogue imports nothing heavy; a test holds them equal to the modules' own tuples.
_REFORM_CLASSIFIERS = ("weighted-knn", "bagged-trees", "logistic-regression")
_REFORM_FEATURE_SETS = ("paper", "relative")
_REFORM_RECONSTRUCTIONS = ("union", "intersection", "correlation")
_REFORM_CALIBRATIONS = ("none", "sigmoid", "isotonic")


def _reform_options(*, features: str, reconstruction: str) -> tuple[Option, ...]:
    return (
        Option(
            "classifier",
            "str",
            "bagged-trees",
            "the pair classifier (its defaults, the paper's settings)",
            choices=_REFORM_CLASSIFIERS,
        ),
        Option(
            "features",
            "str",
            features,
            "pair features: paper (Distance, Effort Angle) or relative (scale-free)",
            choices=_REFORM_FEATURE_SETS,
        ),
        Option(
            "reconstruction",
            "str",
            reconstruction,
            "groups from the pairs: union (the paper's Greedy Reconstruction), intersection, "
            "or correlation clustering over the pair probabilities",
            choices=_REFORM_RECONSTRUCTIONS,
        ),
        Option(
            "calibration",
            "str",
            "none",
            "the classifier's probabilities as they are, or calibrated on held-out time",
            choices=_REFORM_CALIBRATIONS,
        ),
    )


def _reform_trained(
    *,
    classifier: str = "bagged-trees",
    features: str = "paper",
    reconstruction: str = "union",
    calibration: str = "none",
) -> Reform:
    """REFORM, unfitted, with the named options: fitted on training frames before it runs."""
    from reform.classifiers import make_classifier
    from reform.detector import Reform

    return Reform(
        make_classifier(classifier),
        features=features,
        reconstruction=reconstruction,
        calibration=None if calibration == "none" else calibration,
    )


for _name, _features, _reconstruction, _help in (
    ("reform-trained", "paper", "union", "REFORM trained on the training frames given"),
    (
        "reform-relative",
        "relative",
        "union",
        "REFORM with scale-free pair features, trained on the training frames given",
    ),
    (
        "reform-correlation",
        "paper",
        "correlation",
        "REFORM with correlation clustering over its pair probabilities, trained on the "
        "training frames given",
    ),
):
    _register(
        _name,
        _reform_trained,
        help=_help,
        source="built-in",
        options=_reform_options(features=_features, reconstruction=_reconstruction),
        citation=REFORM_CITATION,
        needs="training",
    )

# Temporal filters (reform.smoothing): any detector's partitions steadied over past frames.
_WINDOW = Option(
    "window",
    "float",
    2.0,
    "seconds looked back, the current frame included",
    unit="s",
    low=0.01,
    high=3600.0,
    grid=(0.5, 1.0, 2.0, 4.0),
)
_register(
    "smoothed",
    "reform.smoothing:make_smoothed",
    help="any detector's pairs voted over a sliding window of past frames (sliding majority)",
    source="built-in",
    options=(
        Option(
            "detector",
            "str",
            "gcff",
            "the detector filtered: a catalogued name that runs as it is, or a settings file",
        ),
        _WINDOW,
    ),
)
_register(
    "hysteresis",
    "reform.smoothing:make_hysteresis",
    help="a REFORM configuration's pair probabilities switched with two thresholds over time",
    source="built-in",
    options=(
        Option(
            "detector",
            "str",
            "reform-trained",
            "the REFORM configuration filtered (trained on the training frames given)",
            choices=("reform-trained", "reform-relative", "reform-correlation"),
        ),
        Option("high", "float", 0.7, "probability at which a pair apart joins", low=0.5, high=1.0),
        Option(
            "low", "float", 0.3, "probability at which a pair together parts", low=0.0, high=0.5
        ),
        _WINDOW,
    ),
    citation=REFORM_CITATION,
    needs="training",
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
            "patience",
            "int",
            50,
            "with validation frames (`reform-sim train --validation`), epochs without a better "
            "validation loss before training stops",
            low=1,
            high=100_000,
        ),
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

# The field's non-deep detectors (reform.proximity, reform.dominant_sets, reform.gtcg,
# reform.hough). Defaults as the estimators' signatures (a test holds the two equal); the open
# constants, those with a grid, are chosen on SALSA's training split alone by
# benchmarks/choose_field_defaults.py, which searches these grids.
HUNG_KROSE_CITATION = "Hung, Kröse. Detecting F-formations as dominant sets. ICMI 2011, pp. 231-238"
GTCG_CITATION = (
    "Vascon, Mequanint, Cristani, Hung, Pelillo, Murino. Detecting conversational groups in "
    "images and sequences: A robust game-theoretic approach. CVIU 143, pp. 11-24, 2016"
)
HVFF_CITATION = (
    "Cristani, Bazzani, Paggetti, Fossati, Tosato, Del Bue, Menegaz, Murino. Social "
    "interaction discovery by statistical analysis of F-formations. BMVC 2011"
)
HVFF_MULTISCALE_CITATION = (
    "Setti, Lanz, Ferrario, Murino, Cristani. Multi-scale F-formation discovery for group "
    "detection. ICIP 2013"
)
_FIELD_ORIENTATION = Option(
    "orientation",
    "str",
    "body",
    "the orientation read: body, or head (the head's where seen, the body's where not)",
    choices=("body", "head"),
)
_GLOBAL_CONTEXT = Option(
    "global_context",
    "bool",
    True,
    "stop peeling at the first set not dominant among everyone (Hung & Kröse's rule)",
)


def _seed_option(what: str) -> Option:
    return Option("random_state", "int", 0, f"seeds {what}", low=0, high=2**32 - 1)


def _hough_options(*, radius: float) -> tuple[Option, ...]:
    """The options HVFF and multi-scale HVFF share (votes, accumulator, orientation, seed)."""
    return (
        Option("samples", "int", 100, "votes per person", low=16, high=10_000),
        Option(
            "position_sd",
            "float",
            0.1,
            "standard deviation of a vote's position noise",
            unit="m",
            low=0.0,
            high=10.0,
        ),
        Option(
            "orientation_sd",
            "float",
            0.25,
            "standard deviation of a vote's orientation noise",
            unit="rad",
            low=0.0,
            high=3.14159,
        ),
        Option(
            "radius",
            "float",
            radius,
            "radius of an accumulator cell around a candidate centre",
            unit="m",
            low=0.01,
            high=10.0,
            grid=(0.35, 0.5, 0.7),
        ),
        Option(
            "min_share",
            "float",
            0.2,
            "share of a person's votes a centre must hold for them to back it",
            low=0.01,
            high=1.0,
            grid=(0.1, 0.2, 0.3),
        ),
        _FIELD_ORIENTATION,
        _seed_option("the votes' noise"),
    )


_register(
    "proximity",
    "reform.proximity:Proximity",
    help="proximity baseline: connected components of people within a distance (option "
    "distance, m)",
    source="built-in",
    options=(
        Option(
            "distance",
            "float",
            0.8,
            "largest distance that links two people into one group",
            unit="m",
            low=0.01,
            high=100.0,
            grid=(0.6, 0.8, 1.0, 1.2, 1.5, 2.0),
        ),
    ),
)
_register(
    "dominant-sets",
    "reform.dominant_sets:DominantSets",
    help="dominant sets (Hung & Kröse 2011): proximity affinities between people in each "
    "other's view, sets peeled by replicator dynamics",
    source="built-in",
    options=(
        Option(
            "sigma",
            "float",
            1.6,
            "width of the Gaussian of distance in the affinity",
            unit="m",
            low=0.01,
            high=100.0,
            grid=(0.6, 0.8, 1.0, 1.2, 1.4, 1.6, 1.8, 2.0),
        ),
        Option(
            "field_of_view",
            "float",
            3.84,
            "whole angle within which each must have the other for an affinity (6.2832: "
            "orientation ignored)",
            unit="rad",
            low=0.0,
            high=6.2832,
            grid=(3.1416, 3.84, 4.71),
        ),
        _FIELD_ORIENTATION,
        _GLOBAL_CONTEXT,
    ),
    citation=HUNG_KROSE_CITATION,
)
_register(
    "gtcg",
    "reform.gtcg:Gtcg",
    help="GTCG (Vascon et al. 2016): frustum-overlap affinities, groups as evolutionarily "
    "stable strategies by replicator dynamics, per frame",
    source="built-in",
    options=(
        Option(
            "length",
            "float",
            1.7,
            "the frustum's length (the authors' Cocktail Party 170 cm)",
            unit="m",
            low=0.01,
            high=100.0,
            grid=(1.0, 1.7, 2.5),
        ),
        Option(
            "aperture",
            "float",
            160.0,
            "the frustum's whole aperture (the authors' 160°)",
            unit="deg",
            low=1.0,
            high=360.0,
        ),
        Option("samples", "int", 2000, "samples per frustum", low=10, high=100_000),
        Option(
            "sigma",
            "float",
            0.6,
            "scale of the affinity exp(-JS / sigma) on the Jensen-Shannon divergence (base 2)",
            low=1e-3,
            high=100.0,
            grid=(0.1, 0.2, 0.3, 0.6, 1.0),
        ),
        Option(
            "bin",
            "float",
            0.2,
            "side of a square bin of the frustum histograms",
            unit="m",
            low=0.01,
            high=100.0,
            grid=(0.2, 0.3, 0.5),
        ),
        _FIELD_ORIENTATION,
        _GLOBAL_CONTEXT,
        Option(
            "zero_disjoint",
            "bool",
            False,
            "take exp(-1/sigma), the affinity of frustums sharing no bin, off every affinity "
            "(the authors' code keeps it: two people alone in a frame pair up)",
        ),
        Option(
            "frames",
            "int",
            1,
            "frames whose affinities are averaged, equal weights: the frame and those before it "
            "in its sequence (1: per frame)",
            low=1,
            high=100,
        ),
        _seed_option("the frustum samples"),
    ),
    citation=GTCG_CITATION,
)
_register(
    "hvff",
    "reform.hough:Hvff",
    help="HVFF (Cristani et al. 2011): sampled votes for o-space centres a stride ahead, "
    "accumulated and read greedily by weighted Boltzmann entropy",
    source="built-in",
    options=(
        Option(
            "stride",
            "float",
            0.7,
            "distance of the o-space centre in front of a person",
            unit="m",
            low=0.0,
            high=100.0,
            grid=(0.5, 0.7, 1.0),
        ),
        *_hough_options(radius=0.5),
    ),
    citation=HVFF_CITATION,
)
_register(
    "hvff-multiscale",
    "reform.hough:MultiScaleHvff",
    help="multi-scale HVFF (Setti et al. 2013): votes at the o-space radius of every group "
    "size, a centre of size k making a group of k",
    source="built-in",
    options=(
        Option(
            "spacing",
            "float",
            1.0,
            "distance between neighbours on a group's circle",
            unit="m",
            low=0.01,
            high=100.0,
            grid=(1.0, 1.2, 1.4),
        ),
        Option(
            "max_size",
            "int",
            6,
            "the largest group size with a scale of its own",
            low=2,
            high=20,
        ),
        *_hough_options(radius=0.5),
    ),
    citation=HVFF_MULTISCALE_CITATION,
)
