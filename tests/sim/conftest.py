"""Fixtures of the simulator's tests: a machine of known size, a guard that no work starts, and
a small place's venue twin."""

from __future__ import annotations

import pytest

import sim.episode
from sim import sizing

GiB = 2**30


@pytest.fixture
def machine(monkeypatch):
    """A machine with 16 GiB of memory available (32 GiB with swap) and 100 GiB of free disk,
    whatever runs the tests."""
    monkeypatch.setattr(sizing, "available_memory", lambda: 16 * GiB)
    monkeypatch.setattr(sizing, "total_memory", lambda: 32 * GiB)
    monkeypatch.setattr(sizing, "free_disk", lambda path: 100 * GiB)


@pytest.fixture
def no_work(monkeypatch):
    """Fails any test whose request builds a world: refusals come before any work."""

    def refuse(*args, **kwargs):
        raise AssertionError("a World was built: the request was not refused first")

    monkeypatch.setattr(sim.episode, "World", refuse)


@pytest.fixture(scope="session")
def place_twin(made_once):
    """The label-free twin of ``tests.sim.test_twin._frames(scale=1.5)`` (six people in two
    clusters), named ``"place"``, seed 0: fitted once for every test that reads it, in every
    worker (a fit runs its pilot parties: about 12 s), read from its file. A `sim.twins.Twin` is
    frozen; tests change copies of it."""
    from sim.twins import fit_twin, read_twin, write_twin
    from tests.sim.test_twin import _frames

    return read_twin(
        made_once(
            "place-twin.json",
            lambda path: write_twin(fit_twin(_frames(scale=1.5), name="place"), path),
        )
    )
