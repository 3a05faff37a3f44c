"""DANTE's deep affinity network in PyTorch: the network, its training loop and its inference.

Imported only by `reform.dante` when a DANTE is trained, loaded or asked to predict: this module
imports torch at its top, and torch is the optional extra ``reform-sim[dante]``.

The network (Swofford et al. 2020, Fig. 2; the layer order of their ``build_model``):

* **Dyad transform**: one small network shared by the two people of the pair, applied to each
  (``Linear -> ReLU -> Dropout -> BatchNorm`` per width); the two outputs are concatenated in
  the pair's order (i, j).
* **Context transform** (deep sets): one network shared by every other person of the scene, the
  same layers, then a max over the people, a dropout and a batch normalisation.
* **Final network**: the concatenation [context, dyad_i, dyad_j] through ``Linear -> ReLU ->
  Dropout -> BatchNorm`` per width, then one logit; the affinity is its sigmoid.

Batch normalisation follows Keras' settings (momentum 0.99, epsilon 1e-3), the kernels are
initialised as Keras' ``he_normal`` (last layer ``glorot_normal``) with zero biases.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager

import numpy as np
import torch
from torch import nn

__all__ = ["AffinityNet", "predict_logits", "single_thread", "train_network"]

_BATCH_NORM_EPS = 1e-3  # Keras' BatchNormalization epsilon
_BATCH_NORM_MOMENTUM = 0.01  # PyTorch's convention for Keras' momentum 0.99
_ADAM_EPS = 1e-7  # Keras' Adam epsilon (K.epsilon())
_ADAM_BETAS = (0.9, 0.999)
_LR_DECAY = 1e-5  # Keras' Adam ``decay``: lr / (1 + decay * step)
_CLIP_VALUE = 0.5  # Keras' ``clipvalue``: each gradient entry clipped to [-0.5, 0.5]
_INFERENCE_FLOATS = 1 << 24  # activations held at once while predicting (64 MiB of float32)


class _Block(nn.Module):
    """``Linear -> ReLU -> Dropout -> BatchNorm`` over the last axis, any leading shape."""

    def __init__(self, n_in: int, n_out: int, dropout: float) -> None:
        super().__init__()
        self.linear = nn.Linear(n_in, n_out)
        self.dropout = nn.Dropout(dropout)
        self.norm = nn.BatchNorm1d(n_out, eps=_BATCH_NORM_EPS, momentum=_BATCH_NORM_MOMENTUM)
        nn.init.kaiming_normal_(self.linear.weight, nonlinearity="relu")  # he_normal
        nn.init.zeros_(self.linear.bias)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        shape = x.shape
        y = self.dropout(torch.relu(self.linear(x.reshape(-1, shape[-1]))))
        return self.norm(y).reshape(*shape[:-1], -1)


class AffinityNet(nn.Module):
    """DANTE's network: (context (B, M, d), pair (B, 2, d)) -> affinity logits (B,).

    Args:
        n_features: d, the features of one person (4: x, y, cos, sin of one orientation; 6 with
            a second orientation).
        context_widths: widths of the context transform's shared layers.
        dyad_widths: widths of the dyad transform's shared layers.
        final_widths: widths of the final network's layers before the logit.
        dropout: dropout rate of every layer.
    """

    def __init__(
        self,
        *,
        n_features: int,
        context_widths: Sequence[int],
        dyad_widths: Sequence[int],
        final_widths: Sequence[int],
        dropout: float,
    ) -> None:
        super().__init__()
        self.context = _stack(n_features, context_widths, dropout)
        self.context_dropout = nn.Dropout(dropout)
        self.context_norm = nn.BatchNorm1d(
            context_widths[-1], eps=_BATCH_NORM_EPS, momentum=_BATCH_NORM_MOMENTUM
        )
        self.dyad = _stack(n_features, dyad_widths, dropout)
        self.final = _stack(context_widths[-1] + 2 * dyad_widths[-1], final_widths, dropout)
        self.logit = nn.Linear(final_widths[-1], 1)
        nn.init.xavier_normal_(self.logit.weight)  # glorot_normal
        nn.init.zeros_(self.logit.bias)

    def forward(self, context: torch.Tensor, pair: torch.Tensor) -> torch.Tensor:
        pooled = self.context(context).amax(dim=1)  # deep sets: a max over the other people
        pooled = self.context_norm(self.context_dropout(pooled))
        dyad = self.dyad(pair).flatten(1)  # [dyad_i, dyad_j]: the pair's order matters
        return self.logit(self.final(torch.cat([pooled, dyad], dim=1))).squeeze(1)

    def kernels(self) -> Iterator[torch.Tensor]:
        """The weight matrices the L2 penalty applies to (Keras' kernel_regularizer)."""
        for module in self.modules():
            if isinstance(module, nn.Linear):
                yield module.weight


def _stack(n_in: int, widths: Sequence[int], dropout: float) -> nn.Sequential:
    blocks = []
    for width in widths:
        blocks.append(_Block(n_in, int(width), dropout))
        n_in = int(width)
    return nn.Sequential(*blocks)


@contextmanager
def single_thread(seed: int | None = None) -> Iterator[None]:
    """One torch thread (results independent of the machine's cores) and, with ``seed``, torch's
    random state seeded inside and restored after: the caller's global state is left as it was."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        with torch.random.fork_rng(devices=[]):
            if seed is not None:
                torch.manual_seed(seed)
            yield
    finally:
        torch.set_num_threads(threads)


Batches = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


def train_network(
    net: AffinityNet,
    batches: Batches,
    n_examples: int,
    *,
    epochs: int,
    batch_size: int,
    learning_rate: float,
    l2: float,
    rng: np.random.Generator,
    validation: Callable[[AffinityNet], float] | None = None,
    patience: int | None = None,
    progress: Callable[[int, int, float, float | None], None] | None = None,
) -> list[dict[str, float]]:
    """Trains ``net`` in place as DANTE's code does: binary cross-entropy on the affinity plus an
    L2 penalty on the kernels, Adam (Keras' settings, learning-rate decay, gradients clipped by
    value), shuffled mini-batches; with ``validation`` and ``patience``, stops once the validation
    loss has not improved for ``patience`` epochs and keeps the last weights (Keras'
    EarlyStopping as DANTE uses it).

    Args:
        net: the network, trained in place.
        batches: ``indices -> (context, pair, label)`` float32 arrays for those examples.
        n_examples: how many examples there are.
        epochs: most passes over the examples.
        batch_size: examples per gradient step.
        learning_rate: Adam's initial step size.
        l2: weight of the squared kernels in the loss.
        rng: shuffles the examples.
        validation: ``net -> loss`` on held-out frames (net in eval mode), or None.
        patience: epochs without a better validation loss before stopping, or None.
        progress: called after each epoch with (epoch, epochs, loss, validation loss or None).

    Returns:
        One record per epoch run: ``{"loss": ..., "validation_loss": ...}``.
    """
    optimiser = torch.optim.Adam(
        net.parameters(), lr=learning_rate, betas=_ADAM_BETAS, eps=_ADAM_EPS
    )
    schedule = torch.optim.lr_scheduler.LambdaLR(
        optimiser, lambda step: 1.0 / (1.0 + _LR_DECAY * step)
    )
    bce = nn.BCEWithLogitsLoss()
    history: list[dict[str, float]] = []
    best, waited = math.inf, 0
    for epoch in range(1, epochs + 1):
        net.train()
        order = rng.permutation(n_examples)
        total, seen = 0.0, 0
        for start in range(0, n_examples, batch_size):
            index = order[start : start + batch_size]
            if index.size < 2:  # batch normalisation needs two examples
                continue
            context, pair, label = (torch.from_numpy(a) for a in batches(index))
            loss = bce(net(context, pair), label)
            penalty = sum(weight.square().sum() for weight in net.kernels())
            optimiser.zero_grad()
            (loss + l2 * penalty).backward()
            nn.utils.clip_grad_value_(net.parameters(), _CLIP_VALUE)
            optimiser.step()
            schedule.step()
            total += float(loss.detach()) * index.size
            seen += index.size
        record = {"loss": total / max(seen, 1)}
        validation_loss = None
        if validation is not None:
            net.eval()
            validation_loss = float(validation(net))
            record["validation_loss"] = validation_loss
        history.append(record)
        if progress is not None:
            progress(epoch, epochs, record["loss"], validation_loss)
        if validation_loss is not None and patience is not None:
            if validation_loss < best:
                best, waited = validation_loss, 0
            else:
                waited += 1
                if waited >= patience:
                    break
    net.eval()
    return history


def predict_logits(net: AffinityNet, context: np.ndarray, pair: np.ndarray) -> np.ndarray:
    """Logits of the examples, in chunks that keep the activations under a bound."""
    net.eval()
    widest = max(module.out_features for module in net.modules() if isinstance(module, nn.Linear))
    per_example = max(1, (context.shape[1] + 2) * widest)
    chunk = max(1, _INFERENCE_FLOATS // per_example)
    out = []
    with torch.inference_mode():
        for start in range(0, pair.shape[0], chunk):
            out.append(
                net(
                    torch.from_numpy(context[start : start + chunk]),
                    torch.from_numpy(pair[start : start + chunk]),
                ).numpy()
            )
    return np.concatenate(out) if out else np.zeros(0, dtype=np.float32)
