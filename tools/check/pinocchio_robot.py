"""Compares `skillc robot` with pinocchio on a URDF: tool pose, tool Jacobian and gravity torques
at random configurations inside the joint limits. Not part of the build or the tests.

Setup (outside the repository):  python3 -m venv /tmp/pin-venv && /tmp/pin-venv/bin/pip install pin
Run from the repository root after `cargo build --release`:
    /tmp/pin-venv/bin/python tools/check/pinocchio_robot.py examples/robots/iiwa14.urdf
    /tmp/pin-venv/bin/python tools/check/pinocchio_robot.py examples/robots/lwr4.urdf --samples 200
Exit 1 when any error exceeds --tol (default 1e-6, in m, rad, dimensionless Jacobian entries
and N m).

Conventions matched: skillc's Jacobian is the geometric Jacobian of the tool link's origin with
rows (vx vy vz wx wy wz) in the base frame, which is pinocchio's LOCAL_WORLD_ALIGNED frame
Jacobian; skillc's gravity torques are g(q) (the torques that hold the arm still), pinocchio's
computeGeneralizedGravity. Orientation error is the angle of R_skillc^T R_pinocchio.
"""
import argparse, json, subprocess, sys

import numpy as np
import pinocchio as pin


def skillc_robot(skillc, urdf, tool, q):
    qs = ",".join(repr(float(v)) for v in q)
    out = subprocess.run([skillc, "robot", urdf, "--tool", tool, "--q", qs, "--json"],
                         check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("urdf")
    parser.add_argument("--tool", default="probe_tip")
    parser.add_argument("--samples", type=int, default=100)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--tol", type=float, default=1e-6)
    parser.add_argument("--skillc", default="target/release/skillc")
    args = parser.parse_args()

    model = pin.buildModelFromUrdf(args.urdf)
    model.gravity.linear = np.array([0.0, 0.0, -9.81])
    data = model.createData()
    frame = model.getFrameId(args.tool)
    if frame >= len(model.frames):
        sys.exit("pinocchio: no frame `%s` in %s" % (args.tool, args.urdf))
    lower, upper = model.lowerPositionLimit, model.upperPositionLimit
    rng = np.random.default_rng(args.seed)
    worst = {"position m": 0.0, "orientation rad": 0.0, "jacobian": 0.0, "gravity N m": 0.0}
    for i in range(args.samples):
        q = np.zeros(model.nq) if i == 0 else rng.uniform(lower, upper)
        ours = skillc_robot(args.skillc, args.urdf, args.tool, q)
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacements(model, data)
        placement = data.oMf[frame]
        jac = pin.computeFrameJacobian(model, data, q, frame, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        grav = pin.computeGeneralizedGravity(model, data, q)
        w, x, y, z = ours["tool_quaternion_wxyz"]
        rot = pin.Quaternion(w, x, y, z).toRotationMatrix()
        errors = {
            "position m": np.max(np.abs(np.array(ours["tool_position"]) - placement.translation)),
            "orientation rad": np.linalg.norm(pin.log3(rot.T @ placement.rotation)),
            "jacobian": np.max(np.abs(np.array(ours["jacobian"]) - jac)),
            "gravity N m": np.max(np.abs(np.array(ours["gravity_torque"]) - grav)),
        }
        for key, value in errors.items():
            worst[key] = max(worst[key], float(value))
    print("%s, tool `%s`, %d configurations (q = 0 and %d uniform in the limits, seed %d), pinocchio %s"
          % (args.urdf, args.tool, args.samples, args.samples - 1, args.seed, pin.__version__))
    failed = False
    for key, value in worst.items():
        ok = value <= args.tol
        failed |= not ok
        print("  max |skillc - pinocchio| %-16s %.3e  %s" % (key, value, "ok" if ok else "ABOVE %g" % args.tol))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
