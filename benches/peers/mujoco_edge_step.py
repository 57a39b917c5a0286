"""The witness of runtime/tests/contact_geometry.rs (issue 25, item 2): the same probe path over
the same table end and 5 mm step down in MuJoCo, frictionless, to compare where contact is lost
and the force in steady contact with skillc's rapier plant.

The probe is the suite's 10 mm sphere on three slide joints whose armatures give it the LWR-IV's
effective masses at the suite's start (0.345 kg along x, 3.7 kg along z, from
`Robot::tool_effective_mass`), driven by the suite's Cartesian impedance (3000 N/m in x and y,
1000 N/m in z, 60 N s/m) along the same way points at 30 mm/s. The contact is a spring-damper of
5e4 N/m in every direction (MuJoCo's negative solref), critically damped for the mass along z.

Figures printed, per case: the tip's x where the contact (off_the_end: any force; step_down: the
edge's horizontal push) is lost, and the mean force on the flat at x in [0.53, 0.55] m.
Run with a venv outside the repository:
    /tmp/venv/bin/python benches/peers/mujoco_edge_step.py
"""

import mujoco
import numpy as np

R = 0.01
TOP = 0.300
KXY, KZ, D = 3000.0, 1000.0, 60.0
SPEED = 0.03
MASS = {"x": 0.345, "y": 1.0, "z": 3.7}
K_CONTACT = 5e4


def model(boxes):
    # Negative solref: the contact's stiffness (N/m) and damping (critical for the mass along z).
    solref = f"{-K_CONTACT:.1f} {-2.0 * np.sqrt(K_CONTACT * MASS['z']):.2f}"
    geoms = "\n".join(
        f'<geom type="box" pos="{(a + b) / 2} 0 {top - 0.025}" size="{(b - a) / 2} 0.2 0.025"/>'
        for a, b, top in boxes
    )
    tip_mass = 0.01
    return f"""
<mujoco>
  <option timestep="0.001" integrator="implicitfast" gravity="0 0 0" cone="pyramidal"/>
  <default><geom condim="1" solref="{solref}" solimp="0.99 0.99 0.001"/></default>
  <worldbody>
    {geoms}
    <body name="probe" pos="0.5466 0 0.345">
      <joint name="x" type="slide" axis="1 0 0" armature="{MASS['x'] - tip_mass}"/>
      <joint name="y" type="slide" axis="0 1 0" armature="{MASS['y'] - tip_mass}"/>
      <joint name="z" type="slide" axis="0 0 1" armature="{MASS['z'] - tip_mass}"/>
      <geom name="tip" type="sphere" size="{R}" mass="{tip_mass}"/>
    </body>
  </worldbody>
  <actuator>
    <motor joint="x"/><motor joint="y"/><motor joint="z"/>
  </actuator>
</mujoco>"""


def set_point(start, path, t):
    left, here = t * SPEED, np.array(start)
    for way in path:
        way = np.array(way)
        length = np.linalg.norm(way - here)
        if left <= length:
            return here + (way - here) * (left / max(length, 1e-12))
        left -= length
        here = way
    return here


def run(boxes, path):
    m = mujoco.MjModel.from_xml_string(model(boxes))
    d = mujoco.MjData(m)
    start = np.array([0.5466, 0.0, 0.345])
    total = sum(np.linalg.norm(np.array(b) - np.array(a)) for a, b in zip([start] + path[:-1], path))
    rows = []
    force = np.zeros(6)
    for tick in range(int((total / SPEED + 0.5) / 1e-3)):
        p = start + d.qpos[:3]
        goal = set_point(start, path, tick * 1e-3)
        e = goal - p
        d.ctrl[:] = [KXY * e[0] - D * d.qvel[0], KXY * e[1] - D * d.qvel[1], KZ * e[2] - D * d.qvel[2]]
        mujoco.mj_step(m, d)
        total_force = np.zeros(3)
        for i in range(d.ncon):
            mujoco.mj_contactForce(m, d, i, force)
            frame = d.contact[i].frame.reshape(3, 3)
            # The force on geom 2 (the tip is geom 2 when listed after the boxes) in world axes.
            f_world = frame.T @ force[:3]
            sign = 1.0 if d.contact[i].geom2 == m.ngeom - 1 else -1.0
            total_force += sign * f_world
        rows.append((start + d.qpos[:3], total_force))
    return rows


def figures(rows, horizontal):
    flat = [np.linalg.norm(f) for p, f in rows if 0.53 <= p[0] <= 0.55 and p[2] < TOP + R]
    touched, lost = False, None
    for p, f in rows:
        value = abs(f[0]) if horizontal else np.linalg.norm(f)
        if value > 0.5:
            touched, lost = True, None
        elif touched and lost is None:
            lost = p[0]
    return lost, float(np.mean(flat))


def main():
    z = TOP + R - 10.0 / KZ
    cases = [
        ("off_the_end", [(0.35, 0.58, TOP)], [[0.52, 0.0, z], [0.62, 0.0, z]], False),
        ("step_down", [(0.35, 0.56, TOP), (0.56, 0.75, TOP - 0.005)], [[0.52, 0.0, z], [0.60, 0.0, z]], True),
    ]
    print(f"mujoco {mujoco.__version__}")
    for name, boxes, path, horizontal in cases:
        lost, flat = figures(run(boxes, path), horizontal)
        print(f"{name:12} contact lost at x = {lost:.4f} m, steady force {flat:.3f} N")


if __name__ == "__main__":
    main()
