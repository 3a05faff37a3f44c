"""MuJoCo's ``mj_kinematics`` called from compiled code: motion and kinematics in one loop.

`World.rollout` spends most of its time in two places: the motion kernel (`sim.motion`) and
MuJoCo's kinematics. Calling ``mujoco.mj_kinematics`` from Python once per 100 Hz step costs a
Python round trip per step; batching the steps (``mujoco.batch``) runs ``mj_fwdPosition``, which
does more than kinematics. Here the compiled loop moves the agents, writes the mocap poses and
joint angles straight into an ``MjData``, and calls ``mj_kinematics`` of the MuJoCo library the
``mujoco`` package ships (the same function, found by name), then copies out the body poses.

``NATIVE`` is False when the library file cannot be found next to the ``mujoco`` package (an
unusual build); the world then falls back to ``mujoco.batch``, with identical results.
"""

from __future__ import annotations

import glob
import os

import mujoco
import numba
import numpy as np
from numba import types

from sim.motion import step, workspace, write_pose

# File names of the MuJoCo library inside the mujoco package, by platform.
_PATTERNS = ("libmujoco.so*", "libmujoco*.dylib", "mujoco.dll")


def _library() -> str | None:
    folder = os.path.dirname(mujoco.__file__)
    for pattern in _PATTERNS:
        found = sorted(glob.glob(os.path.join(folder, pattern)))
        if found:
            return found[0]
    return None


LIBRARY = _library()
NATIVE = False
if LIBRARY is not None:
    try:
        import llvmlite.binding as llvm

        llvm.load_library_permanently(LIBRARY)
        NATIVE = True
    except (OSError, RuntimeError):  # pragma: no cover - unusual builds
        NATIVE = False

# void mj_kinematics(const mjModel* m, mjData* d): pointers passed as machine-sized integers.
_mj_kinematics = types.ExternalFunction("mj_kinematics", types.void(types.uintp, types.uintp))


@numba.njit(cache=True)
def advance_with_kinematics(  # pragma: no cover - compiled
    state,
    intent,
    params,
    step0,
    dt,
    margin,
    record_at,
    layout,
    model_address,
    data_address,
    views,
    present,
    bodies,
    out_xy,
    out_quat,
    out_present,
):
    """`sim.motion.advance`, with MuJoCo's kinematics after every recorded step.

    Args:
        state, intent, params, step0, dt, margin, record_at, layout: as for
            `sim.motion.advance`.
        model_address, data_address: ``MjModel._address`` and ``MjData._address``.
        views: `data_views` of that MjData.
        present: (1, n) scratch for the presence of a step.
        bodies: (k,) ids of the bodies to read.
        out_xy: (rows, k, 2) ground-plane positions of ``bodies``, written at recorded rows.
        out_quat: (rows, k, 4) their quaternions.
        out_present: (rows, n) presence.
    """
    data_mocap_pos, data_mocap_quat, data_qpos, data_xpos, data_xquat = views
    records = (data_mocap_pos, data_mocap_quat, data_qpos, present)
    work = workspace(state, params)
    for s in range(record_at.shape[0]):
        step(state, intent, params, dt, margin, work)
        row = record_at[s]
        if row < 0:
            continue
        write_pose(state, params, (step0 + s + 1) * dt, 0, layout, records)
        _mj_kinematics(model_address, data_address)
        for b in range(bodies.shape[0]):
            body = bodies[b]
            out_xy[row, b, 0] = data_xpos[body, 0]
            out_xy[row, b, 1] = data_xpos[body, 1]
            for c in range(4):
                out_quat[row, b, c] = data_xquat[body, c]
        for i in range(present.shape[1]):
            out_present[row, i] = present[0, i]


def data_views(data: mujoco.MjData) -> tuple[np.ndarray, ...]:
    """The views of ``data`` that `advance_with_kinematics` writes and reads.

    Returns:
        ``(mocap_pos, mocap_quat, qpos, xpos, xquat)``: the first three with a leading axis of
        one row, (1, nmocap, 3), (1, nmocap, 4) and (1, nq), written as `sim.motion.write_pose`
        records; then (nbody, 3) and (nbody, 4), read after the kinematics.
    """
    return (
        data.mocap_pos.reshape(1, *data.mocap_pos.shape),
        data.mocap_quat.reshape(1, *data.mocap_quat.shape),
        data.qpos.reshape(1, -1),
        data.xpos,
        data.xquat,
    )
