"""MuJoCo's closed loop on a task like the slide: a torque-controlled 7-joint arm (LWR-IV-like link
lengths and masses, capsule links, a probe with a sphere tip) moves down onto a table, presses
with about 10 N and slides 12 cm, then lifts off: 12 386 steps of 1 ms, as skillc's slide.

Times, per step (median of ROUNDS runs, after a warm-up run):
  - the Python loop: read qpos/qvel/contact force, a Cartesian impedance + force law in numpy
    (Jacobian from mj_jacSite, gravity/Coriolis from qfrc_bias), write ctrl, mj_step;
  - the engine alone: mj_step with the same controls replayed (no Python law).
Run with a venv outside the repository:
    /tmp/venv-mj/bin/python benches/peers/mujoco_press_slide.py [ROUNDS]
"""

import statistics
import sys
import time

import mujoco
import numpy as np

STEPS = 12_386

MJCF = """
<mujoco model="lwr_like_press_slide">
  <compiler angle="radian"/>
  <option timestep="0.001" integrator="implicitfast"/>
  <default>
    <joint damping="0" armature="0.01" limited="true" range="-2.9 2.9"/>
    <geom condim="3" friction="0.4 0.005 0.0001" solref="0.002 1" contype="2" conaffinity="0"/>
    <motor ctrllimited="true" ctrlrange="-176 176"/>
  </default>
  <worldbody>
    <!-- The arm's geoms meet the table only, never each other (as in skillc). -->
    <geom name="table" type="box" pos="0.55 0 0.275" size="0.1 0.05 0.025" contype="1" conaffinity="2"/>
    <body name="l1" pos="0 0 0.11">
      <joint name="j1" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.07" contype="0" conaffinity="0" mass="2.7"/>
      <body name="l2" pos="0 0 0.2005">
        <joint name="j2" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.07" mass="2.7"/>
        <body name="l3" pos="0 0 0.2">
          <joint name="j3" axis="0 0 1"/>
          <geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.07" mass="2.7"/>
          <body name="l4" pos="0 0 0.2">
            <joint name="j4" axis="0 -1 0"/>
            <geom type="capsule" fromto="0 0 0 0 0 0.19" size="0.07" mass="2.7"/>
            <body name="l5" pos="0 0 0.19">
              <joint name="j5" axis="0 0 1"/>
              <geom type="capsule" fromto="0 0 0 0 0 0.078" size="0.07" mass="1.7"/>
              <body name="l6" pos="0 0 0.078">
                <joint name="j6" axis="0 1 0"/>
                <geom type="sphere" size="0.06" mass="1.6"/>
                <body name="l7" pos="0 0 0.05">
                  <joint name="j7" axis="0 0 1"/>
                  <geom type="cylinder" size="0.04 0.025" mass="0.3"/>
                  <geom type="cylinder" pos="0 0 0.075" size="0.015 0.05" mass="0.2"/>
                  <geom name="tip" type="sphere" pos="0 0 0.125" size="0.005" mass="0.01"/>
                  <site name="tip" pos="0 0 0.125"/>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor joint="j1"/><motor joint="j2"/><motor joint="j3"/><motor joint="j4"/>
    <motor joint="j5"/><motor joint="j6"/><motor joint="j7"/>
  </actuator>
</mujoco>
"""

# The probe points straight down: pitch q2 - q4 + q6 = pi about y.
Q0 = np.array([0.0, 0.5, 0.0, -1.5, 0.0, np.pi - 2.0, 0.0])


def build():
    """The model with the table's top 1 mm under the probe tip at Q0 (as in skillc's table scene)."""
    probe = mujoco.MjModel.from_xml_string(MJCF)
    probe_data = mujoco.MjData(probe)
    probe_data.qpos[:] = Q0
    mujoco.mj_forward(probe, probe_data)
    tip = probe_data.site_xpos[probe.site("tip").id]
    table = f'pos="{tip[0] + 0.06} {tip[1]} {tip[2] - 0.005 - 0.001 - 0.025}"'
    model = mujoco.MjModel.from_xml_string(MJCF.replace('pos="0.55 0 0.275"', table))
    data = mujoco.MjData(model)
    data.qpos[:] = Q0
    mujoco.mj_forward(model, data)
    return model, data


def target(t, start):
    """The slide's phases as a tool target: hover, descend, press and slide 12 cm, lift."""
    goal = start.copy()
    if t < 2.0:
        goal[2] = start[2] + 0.05
    elif t < 5.2:
        goal[2] = start[2] + 0.05 - 0.06 * (t - 2.0) / 3.2
    elif t < 9.9:
        goal[2] = start[2] - 0.01
        goal[0] = start[0] + 0.12 * (t - 5.2) / 4.7
    else:
        goal[0] = start[0] + 0.12
        goal[2] = start[2] + 0.05 * min(1.0, (t - 9.9) / 2.4)
    return goal, 5.2 <= t < 9.9


def python_loop(model, data, record=None):
    """The closed loop in Python: impedance in x, y, orientation-free posture; force along z in
    contact."""
    site = model.site("tip").id
    tip_geom = model.geom("tip").id
    jacp = np.zeros((3, model.nv))
    jacr = np.zeros((3, model.nv))
    start = data.site_xpos[site].copy()
    force = np.zeros(6)
    kp, kd = 2000.0, 60.0
    for step in range(STEPS):
        t = step * model.opt.timestep
        goal, pressing = target(t, start)
        fz = 0.0
        for c in range(data.ncon):
            contact = data.contact[c]
            if contact.geom1 == tip_geom or contact.geom2 == tip_geom:
                mujoco.mj_contactForce(model, data, c, force)
                fz += force[0]
        mujoco.mj_jacSite(model, data, jacp, jacr, site)
        err = goal - data.site_xpos[site]
        vel = jacp @ data.qvel
        wrench = kp * err - kd * vel
        if pressing:
            wrench[2] = -10.0 + 0.5 * (10.0 - fz)
        tau = jacp.T @ wrench + data.qfrc_bias + 20.0 * (Q0 - data.qpos) - 3.0 * data.qvel
        data.ctrl[:] = tau
        if record is not None:
            record[step] = tau
        mujoco.mj_step(model, data)


def engine_alone(model, data, controls):
    for step in range(STEPS):
        data.ctrl[:] = controls[step]
        mujoco.mj_step(model, data)


def timed(fn):
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def measure(rounds):
    model, data = build()
    controls = np.zeros((STEPS, model.nu))
    python_loop(model, data, controls)  # warm-up and the controls to replay
    loop, engine = [], []
    for _ in range(rounds):
        model, data = build()
        loop.append(timed(lambda: python_loop(model, data)))
        model, data = build()
        engine.append(timed(lambda: engine_alone(model, data, controls)))
    return statistics.median(loop) / STEPS, statistics.median(engine) / STEPS


if __name__ == "__main__":
    rounds = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    loop, engine = measure(rounds)
    model, data = build()
    python_loop(model, data)
    print(f"mujoco {mujoco.__version__}: python loop {loop * 1e6:.2f} us/step, engine alone {engine * 1e6:.2f} us/step")
