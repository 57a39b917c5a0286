"""The closed loop against MuJoCo in pairs: each round runs MuJoCo's Python loop, its engine
alone, and then `skillc run` of the slide (a process; its user + system CPU time), one right
after the other, and reports each figure per tick and the ratio within every round.

On a shared host the time of the same work varies by 2x or more from minute to minute, which
moves both sides of a pair alike; the median of the per-round ratios is the figure to read, the
medians of the absolute times only say how loaded the host was.

Run from the repository root after `cargo build --release`, with MuJoCo in a venv outside the
repository:
    /tmp/venv-mj/bin/python benches/peers/closed_loop_pairs.py [ROUNDS]
"""

import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import mujoco_press_slide as mj  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SKILLC = os.path.join(ROOT, "target", "release", "skillc")


def skillc_run(learned):
    """CPU seconds (user + system, from the child's rusage) of one `skillc run` of the slide, and
    its ticks (the last state's exit time over the 1 ms step)."""
    proc = subprocess.Popen(
        [SKILLC, "run", "stdlib-skills/slide.skill", "--learned", learned, "--scene", "examples/scenes/table.toml"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )
    stdout = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        sys.exit(f"skillc run failed ({proc.returncode}):\n{stdout}")
    exits = [float(m.group(1)) for m in re.finditer(r"^\s+\S+\s+[0-9.]+\s+([0-9.]+)", stdout, re.MULTILINE)]
    return usage.ru_utime + usage.ru_stime, round(max(exits) / 1e-3)


def main(rounds):
    if not os.path.exists(SKILLC):
        sys.exit(f"{SKILLC} is missing: run `cargo build --release` first")
    with tempfile.TemporaryDirectory() as tmp:
        learned = os.path.join(tmp, "slide.learned.json")
        subprocess.run(
            [SKILLC, "learn", "stdlib-skills/slide.skill", "examples/demos/slide.csv", "-o", learned],
            cwd=ROOT, check=True, stdout=subprocess.DEVNULL,
        )
        model, data = mj.build()
        controls = np.zeros((mj.STEPS, model.nu))
        mj.python_loop(model, data, controls)  # warm-up and the controls to replay
        skillc_run(learned)  # warm-up (page cache)
        rows = []
        for r in range(rounds):
            model, data = mj.build()
            loop = mj.timed(lambda: mj.python_loop(model, data)) / mj.STEPS
            model, data = mj.build()
            engine = mj.timed(lambda: mj.engine_alone(model, data, controls)) / mj.STEPS
            cpu, ticks = skillc_run(learned)
            ours = cpu / ticks
            rows.append((loop, engine, ours))
            print(
                f"round {r + 1}: MuJoCo loop {loop * 1e6:.1f} us, engine {engine * 1e6:.1f} us, "
                f"skillc {ours * 1e6:.1f} us a tick ({ticks} ticks): loop / skillc {loop / ours:.2f}",
                file=sys.stderr,
            )
    loop, engine, ours = (statistics.median(col) for col in zip(*rows))
    ratio_loop = statistics.median(r[0] / r[2] for r in rows)
    ratio_engine = statistics.median(r[1] / r[2] for r in rows)
    print(f"medians of {rounds} rounds, per tick: MuJoCo {time.strftime('%Y-%m-%d')} loop {loop * 1e6:.1f} us, "
          f"engine alone {engine * 1e6:.1f} us; skillc run slide {ours * 1e6:.1f} us (min {min(r[2] for r in rows) * 1e6:.1f})")
    print(f"median of the per-round ratios: MuJoCo loop / skillc {ratio_loop:.2f}, engine / skillc {ratio_engine:.2f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 9)
