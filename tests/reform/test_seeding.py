"""One seed derivation (reform.seeding): keys, independence, the layouts the studies rely on."""

from __future__ import annotations

import numpy as np
import pytest

from reform.seeding import SEED_BITS, SENSOR, WORLD, Role, derive_int, derive_rng, derive_seed


def test_a_key_is_a_spawn_key_of_the_master_seed():
    assert derive_seed(7, Role.STRESS_TEST, 3).spawn_key == (1, 3)
    a = derive_rng(7, Role.STRESS_TEST, 3).random(4)
    b = np.random.default_rng(np.random.SeedSequence(7, spawn_key=(1, 3))).random(4)
    np.testing.assert_array_equal(a, b)


def test_a_datasets_episodes_are_the_children_of_its_master_seed():
    children = np.random.SeedSequence(11).spawn(4)
    for k, child in enumerate(children):
        state = int(child.generate_state(1, dtype=np.uint64)[0] >> np.uint64(64 - SEED_BITS))
        assert derive_int(11, k) == state


def test_an_episodes_world_and_sensor_are_its_two_children():
    world, sensor = np.random.SeedSequence(5).spawn(2)
    assert derive_seed(5, WORLD).spawn_key == world.spawn_key
    assert derive_seed(5, SENSOR).spawn_key == sensor.spawn_key
    np.testing.assert_array_equal(
        derive_seed(5, SENSOR).generate_state(4), sensor.generate_state(4)
    )


def test_roles_are_distinct_and_give_independent_streams():
    assert len({int(r) for r in Role}) == len(Role)
    ints = {derive_int(0, role, 0) for role in Role}
    assert len(ints) == len(Role)
    assert all(0 <= v < 2**SEED_BITS for v in ints)


@pytest.mark.parametrize(
    ("seed", "keys", "message"),
    [
        (-1, (), "seed must be a non-negative integer, got -1"),
        (1.5, (), "seed must be a non-negative integer, got 1.5"),
        (True, (), "seed must be a non-negative integer, got True"),
        (0, (-2,), "a spawn key must be a non-negative integer, got -2"),
        (0, ("a",), "a spawn key must be a non-negative integer, got 'a'"),
    ],
    ids=["negative-seed", "float-seed", "bool-seed", "negative-key", "string-key"],
)
def test_bad_seeds_and_keys(seed, keys, message):
    with pytest.raises(ValueError, match=message):
        derive_seed(seed, *keys)
