"""DANTE (Swofford et al., CSCW 2020): a deep affinity network and dominant-set clustering.

For each ordered pair (i, j) of people in a frame, DANTE predicts the probability that i and j
converse in one group, from the pair and its social context:

* **The pair's frame of reference.** Every person is expressed relative to the pair: the origin
  is the midpoint of i and j, the first axis points from j to i, the second is
  ``(u_y, -u_x)`` (as DANTE's ``shift_data.py``). A person is ``(x, y, cos θ, sin θ)`` in that
  frame, θ their orientation (``orientation="both"``: body, then head, 6 numbers).
* **Dyad and context transforms** (`reform._dante_net`): a network shared by i and j, a network
  shared by every other person max-pooled over them (deep sets), both concatenated into a final
  network whose sigmoid is the pair's affinity.
* **Clustering.** The affinity matrix ``A[i, j] = (a_ij + a_ji) / 2`` is clustered as DANTE's
  ``dominant_sets.py`` does: replicator dynamics find a dominant set (members: weight above
  :data:`MEMBER_WEIGHT`), its people are removed, and again while two or more people remain
  with any affinity between them; everyone left is alone.

Training follows DANTE's code: every ordered pair of every annotated frame, and each frame's
mirror image (y -> -y), labelled 1 when both are in one ground-truth group; binary cross-entropy
plus an L2 penalty on the kernels, Adam with Keras' settings. With validation frames, training
stops once their loss has not improved for ``patience`` epochs (the paper's early stopping).
:func:`fold_splits` gives the paper's five folds (test, validation beside it, train the rest).

Torch is the optional extra ``reform-sim[dante]``: this module imports it only when a DANTE is
trained, loaded or asked to predict; without it, those fail with one line giving the install
command. Models are saved with safetensors and JSON metadata (:meth:`Dante.save`,
:func:`load_dante`), never pickle.
"""

from __future__ import annotations

import inspect
import json
import math
import os
import struct
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator

import reform
from reform.atomic import atomic_open
from reform.frame import Frame, Group
from reform.json_values import JsonError, parse_json
from reform.path_argument import path_argument

__all__ = [
    "BATCH_SIZE",
    "CONTEXT_WIDTHS",
    "DROPOUT",
    "DYAD_WIDTHS",
    "EPOCHS",
    "FAR_AWAY_M",
    "FINAL_WIDTHS",
    "FORMAT",
    "FORMAT_VERSION",
    "INSTALL",
    "L2",
    "LEARNING_RATE",
    "MEMBER_WEIGHT",
    "ORIENTATIONS",
    "PATIENCE",
    "Dante",
    "affinity_matrix",
    "dominant_sets",
    "fold_splits",
    "load_dante",
    "make_dante",
    "torch_available",
]

INSTALL = 'pip install "reform-sim[dante]"'
FORMAT = "reform-sim dante model"
FORMAT_VERSION = 1
ORIENTATIONS = ("body", "head", "both")

# The published architecture of DANTE's Cocktail Party fold-0 model (pair_predictions_29 in its
# repository: test F1 0.843 at T = 2/3, 0.707 at T = 1), and its regularisation.
CONTEXT_WIDTHS = (64, 128)
DYAD_WIDTHS = (16, 64)
FINAL_WIDTHS = (512, 256)
DROPOUT = 0.13
L2 = 1e-7  # weight of the squared kernels in the loss
LEARNING_RATE = 1e-4  # Adam's step size in DANTE's code
BATCH_SIZE = 1024  # examples per step in DANTE's code
EPOCHS = 600  # DANTE's run_models.py: most epochs, early stopping may end sooner
PATIENCE = 50  # epochs without a better validation loss before stopping (DANTE's EarlyStopping)

MEMBER_WEIGHT = 1e-5  # a person is in the dominant set when its replicator weight exceeds this
_REPLICATOR_TOLERANCE = 1e-15  # stop when x'Ax changes by less (DANTE's vector_climb)
_REPLICATOR_MAX_STEPS = 10_000  # a bound DANTE's loop lacks
# A stand-in for the context of a pair alone in the scene: one person far away, facing nowhere
# (DANTE puts it at 50,000 units; 50 m keeps it beyond any conversation without dwarfing the
# scale of the features the network normalises).
FAR_AWAY_M = 50.0  # metres
MAX_MODEL_BYTES = 1 << 28  # bytes (256 MiB): largest model file read (the default net: 1.3 MB)
_MAX_HEADER_BYTES = 1 << 20  # bytes of a safetensors JSON header (the default net: 3 kB)
_METADATA_KEY = "reform_sim"
_PREDICT_PEOPLE = 1 << 20  # context people whose features are made at once while predicting


def torch_available() -> bool:
    """Whether PyTorch (the extra ``reform-sim[dante]``) can be imported."""
    try:
        import torch  # noqa: F401
    except ImportError:
        return False
    return True


def _net_module() -> Any:
    """`reform._dante_net` (imports torch); ImportError with the install command without it."""
    try:
        import reform._dante_net as net
    except ImportError as exc:
        if exc.name not in ("torch", None) and not str(exc.name).startswith("torch."):
            raise
        raise ImportError(f"DANTE needs PyTorch, which is not installed: {INSTALL}") from None
    return net


# ------------------------------------------------------------------------------------------------
# Features


def _orientations(frame: Frame, orientation: str) -> np.ndarray:
    """(n, k) angles, radians: body, head, or both; a missing head (NaN) takes the body's."""
    body = frame.yaw
    head = (
        body if frame.head_yaw is None else np.where(np.isnan(frame.head_yaw), body, frame.head_yaw)
    )
    if orientation == "body":
        return body[:, None]
    if orientation == "head":
        return head[:, None]
    return np.stack([body, head], axis=1)


def _people(frame: Frame, orientation: str) -> tuple[np.ndarray, np.ndarray]:
    """Positions (n, 2) metres and orientation vectors (n, k, 2): cos, sin."""
    angles = _orientations(frame, orientation)
    return frame.position, np.stack([np.cos(angles), np.sin(angles)], axis=-1)


def _pair_features(
    position: np.ndarray,
    facing: np.ndarray,
    i: np.ndarray,
    j: np.ndarray,
    context: np.ndarray,
    flip: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Each example's people in its pair's frame of reference.

    Args:
        position: (F, N, 2) positions of the frames' people, metres (padded rows unused).
        facing: (F, N, k, 2) their orientation vectors.
        i, j: (B, 2) frame and person of the pair's first and second person (frame in column 0).
        context: (B, M) people of the context (person indices in the pair's frame; -1: the far
            stand-in).
        flip: (B,) bool: the mirror image (y -> -y).

    Returns:
        context features (B, M, d) and pair features (B, 2, d), float32, d = 2 + 2k.
    """
    f = i[:, 0]
    pi, pj = position[f, i[:, 1]], position[f, j[:, 1]]
    mid = 0.5 * (pi + pj)
    delta = pi - pj
    norm = np.hypot(delta[:, 0], delta[:, 1])
    u = np.where(norm[:, None] > 0, delta / np.where(norm > 0, norm, 1.0)[:, None], [1.0, 0.0])
    v = np.stack([u[:, 1], -u[:, 0]], axis=1)
    sign = np.where(flip, -1.0, 1.0)

    def express(people: np.ndarray) -> np.ndarray:  # (B, m) person indices -> (B, m, d)
        far = people < 0
        rows = np.where(far, 0, people)
        rel = position[f[:, None], rows] - mid[:, None, :]
        vectors = facing[f[:, None], rows]  # (B, m, k, 2)
        x = np.einsum("bmc,bc->bm", rel, u)
        y = np.einsum("bmc,bc->bm", rel, v) * sign[:, None]
        tx = np.einsum("bmkc,bc->bmk", vectors, u)
        ty = np.einsum("bmkc,bc->bmk", vectors, v) * sign[:, None, None]
        angles = np.stack([tx, ty], axis=-1).reshape(*people.shape, -1)
        out = np.concatenate([x[..., None], y[..., None], angles], axis=-1)
        out[far] = 0.0
        out[far, 0] = out[far, 1] = FAR_AWAY_M
        return out

    pair = express(np.stack([i[:, 1], j[:, 1]], axis=1))
    return express(context).astype(np.float32), pair.astype(np.float32)


def _ordered_pairs(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every ordered pair (i, j), i != j, of n people and the other people of each, (P, n - 2)."""
    i, j = np.nonzero(~np.eye(n, dtype=bool))
    return i, j, _others(i, j, n)


def _others(i: np.ndarray, j: np.ndarray, n: int) -> np.ndarray:
    """(P, n - 2): for each pair, the n - 2 people who are neither i nor j, in order."""
    low, high = np.minimum(i, j)[:, None], np.maximum(i, j)[:, None]
    k = np.arange(max(n - 2, 0))[None, :]  # the k-th person who is neither i nor j
    return k + (k >= low) + (k >= high - 1)


def _together(frame: Frame) -> np.ndarray:
    """(n, n) bool: in one ground-truth group of two or more."""
    label = np.full(frame.n_people, -1)
    index = {int(person): k for k, person in enumerate(frame.ids)}
    for g, group in enumerate(frame.groups or ()):
        if len(group) > 1:
            label[[index[int(p)] for p in group]] = g
    return (label[:, None] == label[None, :]) & (label[:, None] >= 0)


class _Examples:
    """Every ordered pair of every frame with two or more people, and (``mirror``) each again
    mirrored: the batches DANTE trains on, features made per batch."""

    def __init__(
        self, frames: Sequence[Frame], orientation: str, rng: np.random.Generator, mirror: bool
    ) -> None:
        frames = [f for f in frames if f.n_people >= 2]
        self.n_frames = len(frames)
        width = max((f.n_people for f in frames), default=2)
        k = 2 if orientation == "both" else 1
        self.position = np.zeros((len(frames), width, 2))
        self.facing = np.zeros((len(frames), width, k, 2))
        rows, contexts, labels = [], [], []
        context_width = max(width - 2, 1)
        for f, frame in enumerate(frames):
            n = frame.n_people
            self.position[f, :n], self.facing[f, :n] = _people(frame, orientation)
            i, j, others = _ordered_pairs(n)
            if n == 2:
                padded = np.full((len(i), context_width), -1)
            else:  # DANTE fills the missing context slots with people drawn from the context
                fill = others[
                    np.arange(len(i))[:, None],
                    rng.integers(0, n - 2, size=(len(i), context_width - (n - 2))),
                ]
                padded = np.concatenate([others, fill], axis=1)
            rows.append(np.stack([np.full(len(i), f), i, j], axis=1))
            contexts.append(padded)
            labels.append(_together(frame)[i, j])
        self.rows = np.concatenate(rows) if rows else np.zeros((0, 3), dtype=np.int64)
        self.context = np.concatenate(contexts) if contexts else np.zeros((0, 1), dtype=np.int64)
        self.label = np.concatenate(labels) if labels else np.zeros(0, dtype=bool)
        self.copies = 2 if mirror else 1

    def __len__(self) -> int:
        return self.copies * len(self.rows)

    def batch(self, index: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        row = index % len(self.rows)
        flip = index >= len(self.rows)
        r = self.rows[row]
        context, pair = _pair_features(
            self.position, self.facing, r[:, [0, 1]], r[:, [0, 2]], self.context[row], flip
        )
        return context, pair, self.label[row].astype(np.float32)


# ------------------------------------------------------------------------------------------------
# Clustering


def affinity_matrix(n: int, affinity: np.ndarray) -> np.ndarray:
    """(n, n) symmetric affinities from the ordered pairs' ``affinity`` (in `_ordered_pairs`'
    order, i != j): ``A[i, j] = (a_ij + a_ji) / 2``, zero diagonal (DANTE's learned_affinity)."""
    matrix = np.zeros((n, n))
    i, j = np.nonzero(~np.eye(n, dtype=bool))
    matrix[i, j] = affinity
    return 0.5 * (matrix + matrix.T)


def dominant_sets(affinity: np.ndarray) -> list[np.ndarray]:
    """Groups peeled as dominant sets, as DANTE's ``iterate_climb_learned``.

    Replicator dynamics ``x <- x * (A x) / (x' A x)`` from the barycentre of the people left run
    until ``x' A x`` changes by less than 1e-15; the people whose weight exceeds
    :data:`MEMBER_WEIGHT` form a group and are removed; again while two or more people are left
    and some affinity joins them.

    Args:
        affinity: (n, n) symmetric, non-negative, zero diagonal.

    Returns:
        The groups, each an array of row indices, in the order found (people in none are alone).
    """
    a = np.asarray(affinity, dtype=np.float64)
    left = np.ones(a.shape[0], dtype=bool)
    groups = []
    while left.sum() > 1:
        masked = a * left[:, None] * left[None, :]
        if masked.sum() <= 0:
            break
        x = left / left.sum()
        value = x @ masked @ x
        for _ in range(_REPLICATOR_MAX_STEPS):
            pull = masked @ x
            total = x @ pull
            if total <= 0:
                break
            x = x * pull / total
            new = x @ masked @ x
            if abs(new - value) <= _REPLICATOR_TOLERANCE:
                break
            value = new
        members = (x > MEMBER_WEIGHT) & left
        if not members.any():
            break
        groups.append(np.flatnonzero(members))
        left &= ~members
    return groups


# ------------------------------------------------------------------------------------------------
# Folds


def fold_splits(
    frames: Sequence[Frame] | int, k: int = 5
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """DANTE's folds over frames in their order (``build_dataset.py``): fold ``f`` tests the
    ``f``-th contiguous fifth; validation is half a fold on each side of it (a whole fold after
    the first fold's, before the last's); training is every frame outside both.

    Args:
        frames: the frames in time order (sequences one after the other), or how many.
        k: how many folds (DANTE: 5).

    Returns:
        ``k`` triples (train, validation, test) of frame indices, each sorted.

    Raises:
        ValueError: k below 2, or too few frames for k folds of at least two frames.
    """
    n_frames = frames if isinstance(frames, (int, np.integer)) else len(frames)
    if isinstance(k, bool) or not isinstance(k, int) or k < 2:
        raise ValueError(f"k must be an integer of at least 2, got {k!r}")
    if isinstance(n_frames, bool) or not isinstance(n_frames, (int, np.integer)):
        raise ValueError(f"n_frames must be a number of frames, got {n_frames!r}")
    if n_frames < 2 * k:
        raise ValueError(f"n_frames must be at least {2 * k} for {k} folds, got {n_frames}")
    n = int(n_frames)
    half = int(n / k / 2)
    splits = []
    for fold in range(k):
        start, end = int(n / k * fold), int(n / k * (fold + 1))
        if start == 0:
            spans = [(end, end + 2 * half)]
        elif fold == k - 1:
            spans = [(start - 2 * half, start)]
        else:
            spans = [(start - half, start), (end, end + half)]
        low = min(s for s, _ in [*spans, (start, end)])
        high = max(e for _, e in [*spans, (start, end)])
        validation = np.concatenate([np.arange(s, e) for s, e in spans])
        train = np.concatenate([np.arange(0, low), np.arange(high, n)])
        splits.append((train, np.sort(validation), np.arange(start, end)))
    return splits


# ------------------------------------------------------------------------------------------------
# The estimator


class Dante(BaseEstimator):
    """DANTE: a deep affinity network over pairs in their social context, clustered as dominant
    sets (Swofford et al., CSCW 2020).

    Args:
        orientation: the orientation each person carries: ``"body"``, ``"head"`` (a missing head
            takes the body's) or ``"both"`` (DANTE's SALSA input).
        epochs: most passes over the training pairs.
        learning_rate: Adam's step size.
        batch_size: pairs per gradient step.
        patience: with validation frames, epochs without a better validation loss before
            training stops.
        context_widths: widths of the context transform's layers.
        dyad_widths: widths of the dyad transform's layers.
        final_widths: widths of the final network's layers.
        dropout: dropout rate of every layer.
        l2: weight of the squared kernels in the loss.
        random_state: seeds the weights, the shuffling, dropout and the context padding; one
            seed, one model (torch runs on one thread while training and predicting).

    Attributes:
        net_: the trained network (`reform._dante_net.AffinityNet`).
        n_features_in_: numbers per person (4, or 6 with ``orientation="both"``).
        history_: one record per epoch run (loss, validation loss).
        training_summary_: frames, pairs, pairs together, epochs run.
    """

    def __init__(
        self,
        *,
        orientation: str = "body",
        epochs: int = EPOCHS,
        learning_rate: float = LEARNING_RATE,
        batch_size: int = BATCH_SIZE,
        patience: int = PATIENCE,
        context_widths: tuple[int, ...] = CONTEXT_WIDTHS,
        dyad_widths: tuple[int, ...] = DYAD_WIDTHS,
        final_widths: tuple[int, ...] = FINAL_WIDTHS,
        dropout: float = DROPOUT,
        l2: float = L2,
        random_state: int = 0,
    ) -> None:
        self.orientation = orientation
        self.epochs = epochs
        self.learning_rate = learning_rate
        self.batch_size = batch_size
        self.patience = patience
        self.context_widths = context_widths
        self.dyad_widths = dyad_widths
        self.final_widths = final_widths
        self.dropout = dropout
        self.l2 = l2
        self.random_state = random_state

    # -- parameters -------------------------------------------------------------------------

    def _check_params(self) -> None:
        if self.orientation not in ORIENTATIONS:
            raise ValueError(
                f"orientation must be one of {', '.join(ORIENTATIONS)}, got {self.orientation!r}"
            )
        for name, low in (("epochs", 1), ("batch_size", 2), ("patience", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
                raise ValueError(f"{name} must be an integer of at least {low}, got {value!r}")
        for name in ("context_widths", "dyad_widths", "final_widths"):
            widths = getattr(self, name)
            if (
                not isinstance(widths, (tuple, list))
                or not widths
                or not all(
                    isinstance(w, (int, np.integer)) and not isinstance(w, bool) and 1 <= w <= 4096
                    for w in widths
                )
            ):
                raise ValueError(
                    f"{name} must be a non-empty sequence of layer widths from 1 to 4096, "
                    f"got {widths!r}"
                )
        if not (isinstance(self.learning_rate, (int, float)) and 0 < self.learning_rate <= 1):
            raise ValueError(f"learning_rate must be in (0, 1], got {self.learning_rate!r}")
        if not (isinstance(self.dropout, (int, float)) and 0 <= self.dropout < 1):
            raise ValueError(f"dropout must be in [0, 1), got {self.dropout!r}")
        if not (isinstance(self.l2, (int, float)) and 0 <= self.l2 < math.inf):
            raise ValueError(f"l2 must be a finite number >= 0, got {self.l2!r}")
        seed = self.random_state
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f"random_state must be an integer >= 0, got {seed!r}")

    @property
    def _n_features(self) -> int:
        return 6 if self.orientation == "both" else 4

    def _architecture(self) -> dict[str, Any]:
        return {
            "n_features": self._n_features,
            "context_widths": [int(w) for w in self.context_widths],
            "dyad_widths": [int(w) for w in self.dyad_widths],
            "final_widths": [int(w) for w in self.final_widths],
            "dropout": float(self.dropout),
        }

    # -- training ---------------------------------------------------------------------------

    def fit(
        self,
        frames: Sequence[Frame],
        *,
        validation: Sequence[Frame] | None = None,
        progress: Callable[[int, int, float, float | None], None] | None = None,
    ) -> Dante:
        """Trains the network on the annotated frames' ordered pairs and their mirror images.

        Args:
            frames: annotated frames (frames without ground truth are skipped).
            validation: annotated frames for early stopping (``patience``), or None to run
                ``epochs`` epochs.
            progress: called after each epoch with (epoch, epochs, loss, validation loss or
                None), e.g. to print progress.

        Returns:
            self.

        Raises:
            ImportError: PyTorch is not installed (one line with the install command).
            ValueError: a parameter out of range, or no annotated pair to learn from.
        """
        self._check_params()
        net_module = _net_module()
        training = [f for f in frames if f.groups is not None]
        held_out = None if validation is None else [f for f in validation if f.groups is not None]
        seeds = np.random.SeedSequence(int(self.random_state)).spawn(4)
        examples = _Examples(training, self.orientation, np.random.default_rng(seeds[0]), True)
        if len(examples) < 2:
            raise ValueError(
                f"DANTE needs annotated frames with two or more people to learn from; got "
                f"{len(training)} annotated frames of {len(frames)} with {len(examples) // 2} pairs"
            )
        check = None
        if held_out:
            check = _Examples(held_out, self.orientation, np.random.default_rng(seeds[1]), True)
            check = check if len(check) >= 1 else None
        torch_seed = int(np.random.default_rng(seeds[2]).integers(2**31))
        with net_module.single_thread(torch_seed):
            net = net_module.AffinityNet(**self._architecture())

            def validation_loss(model: Any) -> float:
                index = np.arange(len(check))
                context, pair, label = check.batch(index)
                logits = net_module.predict_logits(model, context, pair)
                p = 1.0 / (1.0 + np.exp(-logits.astype(np.float64)))
                p = np.clip(p, 1e-7, 1 - 1e-7)
                loss = -np.mean(label * np.log(p) + (1 - label) * np.log(1 - p))
                penalty = sum(float(w.detach().square().sum()) for w in model.kernels())
                return float(loss + self.l2 * penalty)

            history = net_module.train_network(
                net,
                examples.batch,
                len(examples),
                epochs=int(self.epochs),
                batch_size=int(self.batch_size),
                learning_rate=float(self.learning_rate),
                l2=float(self.l2),
                rng=np.random.default_rng(seeds[3]),
                validation=validation_loss if check is not None else None,
                patience=int(self.patience),
                progress=progress,
            )
        self.net_ = net
        self.n_features_in_ = self._n_features
        self.history_ = history
        pairs = len(examples.rows)
        self.training_summary_ = {
            "frames": examples.n_frames,
            "ordered_pairs": pairs,
            "together_pairs": int(examples.label.sum()),
            "validation_frames": 0 if check is None else check.n_frames,
            "epochs_run": len(history),
            "final_loss": history[-1]["loss"] if history else math.nan,
        }
        return self

    # -- prediction -------------------------------------------------------------------------

    def _check_fitted(self) -> None:
        if not hasattr(self, "net_"):
            raise ValueError(
                "this DANTE is not trained: fit it on annotated frames (reform-sim train "
                "--detector dante) or load a model file (model=FILE)"
            )

    def affinities(self, frame: Frame) -> np.ndarray:
        """(n, n) symmetric pair affinities of ``frame``'s people in [0, 1], zero diagonal."""
        self._check_fitted()
        n = frame.n_people
        if n < 2:
            return np.zeros((n, n))
        net_module = _net_module()
        i, j = np.nonzero(~np.eye(n, dtype=bool))
        position, facing = _people(frame, self.orientation)
        logits = np.empty(len(i))
        step = max(1, _PREDICT_PEOPLE // max(n - 2, 1))  # pairs whose features are held at once
        for start in range(0, len(i), step):
            a, b = i[start : start + step], j[start : start + step]
            others = _others(a, b, n) if n > 2 else np.full((len(a), 1), -1)
            zeros = np.zeros(len(a), dtype=np.int64)
            context, pair = _pair_features(
                position[None],
                facing[None],
                np.stack([zeros, a], axis=1),
                np.stack([zeros, b], axis=1),
                others,
                np.zeros(len(a), dtype=bool),
            )
            with net_module.single_thread():
                logits[start : start + step] = net_module.predict_logits(self.net_, context, pair)
        return affinity_matrix(n, 1.0 / (1.0 + np.exp(-logits)))

    def predict(self, frames: Sequence[Frame]) -> list[list[Group]]:
        """One partition per frame: the dominant sets of its affinity matrix, everyone else alone.

        Raises:
            ValueError: the model is not trained.
            ImportError: PyTorch is not installed (one line with the install command).
        """
        self._check_fitted()
        out = []
        for frame in frames:
            ids = [int(person) for person in frame.ids]
            found = dominant_sets(self.affinities(frame)) if len(ids) > 1 else []
            grouped = {int(k) for group in found for k in group}
            partition = [tuple(ids[int(k)] for k in group) for group in found]
            partition += [(ids[k],) for k in range(len(ids)) if k not in grouped]
            out.append(partition)
        return out

    # -- persistence ------------------------------------------------------------------------

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Writes the trained model to one safetensors file (weights) with JSON metadata
        (format, versions, parameters, architecture, training summary), atomically.

        Returns:
            The path written (conventionally ``*.safetensors``).
        """
        self._check_fitted()
        path = path_argument(path, name="path", function="Dante.save")
        from safetensors.numpy import save as save_arrays

        tensors = {
            name: np.ascontiguousarray(value.detach().cpu().numpy())
            for name, value in self.net_.state_dict().items()
        }
        metadata = {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "versions": _versions(),
            "params": _json_params(self.get_params()),
            "architecture": self._architecture(),
            "training": self.training_summary_,
            "history": self.history_,
        }
        data = save_arrays(tensors, metadata={_METADATA_KEY: json.dumps(metadata)})
        with atomic_open(path, "wb") as handle:
            handle.write(data)
        return path


def make_dante(*, model: str | os.PathLike[str] | None = None, **params: Any) -> Dante:
    """The catalogue's ``dante``: the model file ``model`` (written by ``reform-sim train
    --detector dante``) loaded, or, without one, an untrained DANTE of ``params`` to fit.

    Raises:
        reform.DetectorError: one line: PyTorch is not installed (with the install command), a
            training option given with a trained model, or a model file that cannot be loaded.
    """
    from reform.detectors import DetectorError

    given = f" (model={os.fspath(model)!r})" if model is not None else ""
    if not torch_available():
        raise DetectorError(
            f"detector 'dante'{given} needs PyTorch, which is not installed: {INSTALL}"
        )
    if model is None:
        return Dante(**params)
    defaults = {
        name: parameter.default for name, parameter in inspect.signature(Dante).parameters.items()
    }
    changed = [name for name, value in params.items() if value != defaults.get(name, value)]
    if changed:
        raise DetectorError(
            f"detector 'dante': {', '.join(changed)} train a new model; model={os.fspath(model)!r} "
            "is trained already (give one or the other)"
        )
    try:
        return load_dante(model)
    except (OSError, ValueError) as exc:
        raise DetectorError(f"detector 'dante': {' '.join(str(exc).split())}") from None


def _versions() -> dict[str, str]:
    import torch

    return {"reform_sim": reform.__version__, "torch": torch.__version__.split("+")[0]}


def _json_params(params: dict[str, Any]) -> dict[str, Any]:
    return {
        key: [int(v) for v in value] if isinstance(value, (tuple, list)) else value
        for key, value in params.items()
    }


def load_dante(path: str | os.PathLike[str], *, max_bytes: int = MAX_MODEL_BYTES) -> Dante:
    """Reads a DANTE model written by :meth:`Dante.save`, checked before it is used.

    The file must be a safetensors file (no code runs from it) whose metadata says it is a
    reform-sim DANTE model of this format version, whose parameters and architecture are valid,
    and whose tensors are exactly the network's, of its shapes and finite.

    Raises:
        FileNotFoundError: the file does not exist.
        ValueError: one line naming the file: a folder, above ``max_bytes``, another detector's
            model (a REFORM ``.skops``), not a safetensors file, a malformed or corrupt one, or
            weights that do not fit the network.
        ImportError: PyTorch is not installed (one line with the install command).
    """
    path = path_argument(path, name="path", function="load_dante")
    data = _read(path, max_bytes)
    metadata = _metadata(path, data)
    net_module = _net_module()
    import torch
    from safetensors.numpy import load as load_arrays

    params = metadata.get("params")
    architecture = metadata.get("architecture")
    if not isinstance(params, dict) or not isinstance(architecture, dict):
        raise ValueError(f"{path}: the DANTE model's metadata lacks its params or architecture")
    try:
        model = Dante(
            **{
                key: tuple(value) if isinstance(value, list) else value
                for key, value in params.items()
            }
        )
        model._check_params()
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{path}: the DANTE model's parameters are invalid: {exc}") from None
    if architecture != model._architecture():
        raise ValueError(f"{path}: the DANTE model's architecture disagrees with its parameters")
    try:
        arrays = load_arrays(data)
    except Exception as exc:  # safetensors on a file's bytes: its own error types
        raise ValueError(f"{path}: corrupt DANTE model file ({_one_line(exc)})") from None
    with net_module.single_thread():
        net = net_module.AffinityNet(**architecture)
    expected = net.state_dict()
    if set(arrays) != set(expected):
        missing = sorted(set(expected) - set(arrays))
        extra = sorted(set(arrays) - set(expected))
        raise ValueError(
            f"{path}: the DANTE model's tensors do not fit its network (missing "
            f"{missing[:3]}, unexpected {extra[:3]})"
        )
    state = {}
    for name, reference in expected.items():
        array = arrays[name]
        if reference.dim() == 0 and array.shape == (1,):  # a scalar is written as one element
            array = array.reshape(())
        if tuple(array.shape) != tuple(reference.shape) or array.dtype != _numpy_dtype(reference):
            raise ValueError(
                f"{path}: tensor {name} is {array.dtype}{list(array.shape)}, expected "
                f"{_numpy_dtype(reference)}{list(reference.shape)}"
            )
        if array.dtype.kind == "f" and not np.isfinite(array).all():
            raise ValueError(f"{path}: tensor {name} holds NaN or infinite values")
        state[name] = torch.from_numpy(array.copy())
    net.load_state_dict(state, strict=True)
    net.eval()
    model.net_ = net
    model.n_features_in_ = architecture["n_features"]
    model.history_ = list(metadata.get("history") or [])
    model.training_summary_ = dict(metadata.get("training") or {})
    return model


def _numpy_dtype(tensor: Any) -> np.dtype:
    return tensor.detach().numpy().dtype


def _one_line(exc: BaseException) -> str:
    return " ".join(f"{type(exc).__name__}: {exc}".split())[:300]


def _read(path: Path, max_bytes: int) -> bytes:
    if isinstance(max_bytes, bool) or not isinstance(max_bytes, int) or max_bytes < 1:
        raise ValueError(f"max_bytes must be a positive number of bytes, got {max_bytes!r}")
    if path.is_dir():
        raise ValueError(f"model file {path} is a folder: expected a DANTE model (.safetensors)")
    if not path.exists():
        raise FileNotFoundError(f"model file {path} does not exist")
    try:
        size = path.stat().st_size
        if size > max_bytes:
            raise ValueError(
                f"{path}: the file is {size:,} bytes, above the limit of {max_bytes:,} bytes"
            )
        return path.read_bytes()
    except OSError as exc:
        raise ValueError(f"model file {path} cannot be read: {exc.strerror or exc}") from None


def _metadata(path: Path, data: bytes) -> dict[str, Any]:
    """The reform-sim metadata of a safetensors file, its header checked by hand first."""
    if data[:4] == b"PK\x03\x04":
        raise ValueError(
            f"{path}: a REFORM model file (skops archive), not a DANTE model: use it with the "
            "detector reform"
        )
    if len(data) < 8:
        raise ValueError(f"{path}: not a DANTE model file (not a safetensors file: too short)")
    (length,) = struct.unpack("<Q", data[:8])
    if length < 2 or length > min(_MAX_HEADER_BYTES, len(data) - 8):
        raise ValueError(
            f"{path}: not a DANTE model file (not a safetensors file: header of {length:,} bytes "
            f"in a file of {len(data):,})"
        )
    try:
        header = parse_json(data[8 : 8 + length])
    except JsonError:
        raise ValueError(
            f"{path}: not a DANTE model file (not a safetensors file: its header is not JSON)"
        ) from None
    text = header.get("__metadata__", {}).get(_METADATA_KEY) if isinstance(header, dict) else None
    if not isinstance(text, str):
        raise ValueError(f"{path}: a safetensors file, but not a DANTE model written by reform-sim")
    try:
        metadata = parse_json(text)
    except JsonError:
        raise ValueError(f"{path}: the DANTE model's metadata is not JSON") from None
    if not isinstance(metadata, dict) or metadata.get("format") != FORMAT:
        raise ValueError(f"{path}: a safetensors file, but not a DANTE model written by reform-sim")
    if metadata.get("format_version") != FORMAT_VERSION:
        raise ValueError(
            f"{path}: a DANTE model of format version {metadata.get('format_version')!r}; this "
            f"reform-sim reads version {FORMAT_VERSION}"
        )
    return metadata
