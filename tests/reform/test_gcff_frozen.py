"""GCFF's labels on seeded frames of 6 to 700 people, frozen before its speed paths were written.

Every path ``gcff_labels`` takes (plain Python up to 12 people, the dense sweep up to 64, the
crowd's sparse sweep beyond) must keep giving these labels: the speed work changes no answer.
The frames are random and adversarial (positions and facings on a lattice, so costs tie
exactly; people packed three to a square metre, so every neighbourhood holds many).
"""

from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest

from reform.gcff import gcff_labels

# (kind, people, stride m, mdl m², seed, groups, first 16 hex digits of the SHA-256 of the
# labels as little-endian int64): computed by reform/gcff.py at commit 7548f15, before the
# plain-Python path for a few people and the crowd sweep's kept evaluations.
FROZEN = [
    ("hall", 6, 0.7, 1.0, 0, 5, "2415754049a88e5c"),
    ("hall", 12, 0.5, 2.0, 1, 5, "722babc34a245562"),
    ("hall", 13, 0.7, 1.0, 2, 10, "074b8844a639be2e"),
    ("hall", 40, 0.5, 2.0, 3, 19, "a720d0be6fd5852d"),
    ("hall", 200, 0.7, 1.0, 4, 109, "cb03a11b3c2f1ef4"),
    ("hall", 300, 0.7, 3.0, 5, 97, "a090820d26c1c971"),
    ("hall", 700, 0.6, 1.0, 6, 384, "e76ed3629742a548"),
    ("circles", 6, 0.7, 1.0, 7, 5, "8dde36d36e3efee4"),
    ("circles", 12, 0.5, 2.0, 8, 7, "f2fb87b3cf19c2d2"),
    ("circles", 13, 0.7, 1.0, 9, 8, "18679531859f49fe"),
    ("circles", 40, 0.5, 2.0, 10, 28, "40cfa9d2b4d6fa37"),
    ("circles", 200, 0.7, 1.0, 11, 138, "aa03925cef609d39"),
    ("circles", 300, 0.7, 3.0, 12, 217, "4332adab76e1988d"),
    ("circles", 700, 0.6, 1.0, 13, 482, "d7e25add670800f1"),
    ("lattice", 6, 0.7, 1.0, 14, 3, "02ae6808a6538b58"),
    ("lattice", 12, 0.5, 2.0, 15, 3, "8bbb0b8c395c1aaa"),
    ("lattice", 13, 0.7, 1.0, 16, 4, "ebdf96c221fd08ed"),
    ("lattice", 40, 0.5, 2.0, 17, 7, "cf1e455f769b9ac8"),
    ("lattice", 200, 0.7, 1.0, 18, 48, "dbfa4cc8a13c71d2"),
    ("lattice", 300, 0.7, 3.0, 19, 54, "bf21ab087988fd76"),
    ("lattice", 700, 0.6, 1.0, 20, 168, "09096927277c8ef8"),
    ("packed", 6, 0.7, 1.0, 21, 3, "1abe43514e8b36bf"),
    ("packed", 12, 0.5, 2.0, 22, 3, "4fbdaf18428013cd"),
    ("packed", 13, 0.7, 1.0, 23, 4, "a99133f700c56314"),
    ("packed", 40, 0.5, 2.0, 24, 8, "fce2bd26a1beb3b3"),
    ("packed", 200, 0.7, 1.0, 25, 50, "133d9d72ba92cb83"),
    ("packed", 300, 0.7, 3.0, 26, 52, "8b5656de6c036ba5"),
    ("packed", 700, 0.6, 1.0, 27, 170, "441edcfbcd76c2ec"),
]


def frame(kind: str, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` people (metres, radians) of one kind, from ``seed`` (uniform draws only)."""
    u = np.random.default_rng(seed).random((n, 4))
    if kind == "hall":  # anywhere, facing anywhere, half a person per square metre
        side = math.sqrt(n / 0.5)
        return u[:, :2] * side, (u[:, 2] - 0.5) * 2 * math.pi
    if kind == "circles":  # around centres 3 m apart, facing them
        slot = np.cumsum(2 + (u[:, 3] * 4).astype(int)) // 5
        per_row = max(1, int(math.sqrt(n / 3)))
        centre = 3.0 * np.stack([slot % per_row, slot // per_row], axis=1)
        angle = u[:, 0] * 2 * math.pi
        position = centre + 0.6 * np.stack([np.cos(angle), np.sin(angle)], axis=1)
        return position + (u[:, 1:3] - 0.5) * 0.1, angle + math.pi + (u[:, 3] - 0.5) * 0.5
    if kind == "lattice":  # positions and facings on a lattice: exact ties everywhere
        side = max(2, int(math.sqrt(n)))
        return np.floor(u[:, :2] * side) * 0.6, np.floor(u[:, 2] * 8) * (math.pi / 4)
    # "packed": three people per square metre
    side = math.sqrt(n / 3.0)
    return u[:, :2] * side, (u[:, 2] - 0.5) * 2 * math.pi


def digest(labels: np.ndarray) -> str:
    return hashlib.sha256(np.asarray(labels, dtype="<i8").tobytes()).hexdigest()[:16]


@pytest.mark.parametrize(
    ("kind", "n", "stride", "mdl", "seed", "groups", "expected"),
    FROZEN,
    ids=[f"{kind}-{n}-seed{seed}" for kind, n, *_, seed, _, _ in FROZEN],
)
def test_labels_as_frozen(kind, n, stride, mdl, seed, groups, expected):
    position, yaw = frame(kind, n, seed)
    labels = gcff_labels(position, yaw, stride=stride, mdl=mdl)
    assert int(labels.max()) + 1 == groups
    assert digest(labels) == expected
