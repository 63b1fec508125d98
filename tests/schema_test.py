#!/usr/bin/env python3
"""CTest schema_validates_configs: `tailsim schema` (and `--robot`) checked with python3-jsonschema
against every YAML file under configs/ (configs/design/'s optimize and maneuver files included), the YAML examples of README.md and docs/experiment-format.md,
and negative cases the schema must reject (an unknown key, a value out of range, a bad enum)."""
import glob, json, os, re, subprocess, sys

import jsonschema
import yaml

src, tailsim = sys.argv[1], sys.argv[2]
exp_schema = json.loads(subprocess.run([tailsim, "schema"], check=True, capture_output=True, text=True).stdout)
robot_schema = json.loads(subprocess.run([tailsim, "schema", "--robot"], check=True, capture_output=True, text=True).stdout)
jsonschema.Draft202012Validator.check_schema(exp_schema)
jsonschema.Draft202012Validator.check_schema(robot_schema)
exp_v = jsonschema.Draft202012Validator(exp_schema)
robot_v = jsonschema.Draft202012Validator(robot_schema)


def load(text):
    # YAML 1.1 would read `1: {...}` keys as ints; the schema speaks JSON (string keys).
    d = yaml.safe_load(text)
    return json.loads(json.dumps(d, default=str)) if d is not None else d


failures = []
checked = 0
for f in sorted(glob.glob(os.path.join(src, "configs", "**", "*.yaml"), recursive=True)):
    v = robot_v if os.sep + "robots" + os.sep in f else exp_v
    d = load(open(f).read())
    errs = list(v.iter_errors(d))
    checked += 1
    if errs:
        failures.append(f"{f}: {errs[0].message} at {list(errs[0].absolute_path)}")

# The complete examples of README.md and the format docs (```yaml blocks with name: and robot:, or
# name: and kind: optimize / maneuver).
for doc in ("README.md", os.path.join("docs", "experiment-format.md"), os.path.join("docs", "design-a-tail-stroke.md")):
    text = open(os.path.join(src, doc)).read()
    for block in re.findall(r"```yaml\n(.*?)```", text, re.S):
        try:
            d = load(block)
        except yaml.YAMLError:
            continue
        if not (isinstance(d, dict) and "name" in d and ("robot" in d or d.get("kind") in ("optimize", "maneuver"))):
            continue
        checked += 1
        errs = list(exp_v.iter_errors(d))
        if errs:
            failures.append(f"{doc} example {d['name']}: {errs[0].message}")

base = {"name": "x", "robot": "paper", "trajectory": {"dtheta_deg": -90, "dT_s": 0.25}}
assert not list(exp_v.iter_errors(base)), "the minimal experiment must pass"
assert not list(exp_v.iter_errors({**base, "trajectory": {"theta0_deg": {"range": [0, 90, 15]}, "dtheta_deg": -90, "dT_s": 0.25}}))
assert not list(exp_v.iter_errors({**base, "trajectory": {"family": "spline", "knots_deg": [[30, 10, -40], [0, 20]], "dT_s": 0.3}}))
assert not list(exp_v.iter_errors({**base, "trajectory": {"family": "spline", "knots_deg": [30, {"sweep": [0, 10]}], "dT_s": 0.3}}))
negatives = {
    "spline knot out of range": {**base, "trajectory": {"family": "spline", "knots_deg": [30, 500], "dT_s": 0.3}},
    "one spline knot": {**base, "trajectory": {"family": "spline", "knots_deg": [30], "dT_s": 0.3}},
    "unknown family": {**base, "trajectory": {"family": "bezier", "knots_deg": [30, 0], "dT_s": 0.3}},
    "unknown top-level key": {**base, "colour": "red"},
    "unknown analytic key": {**base, "analytic": {"solvr": "fixed"}},
    "render fps out of range": {**base, "render": {"fps": 1000}},
    "odd render width": {**base, "render": {"width": 641}},
    "bad enum": {**base, "mujoco": {"integrator": "RK45"}},
    "negative timestep": {**base, "mujoco": {"timestep_s": -1}},
    "condim 2": {**base, "mujoco": {"condim": 2}},
    "w_ss out of range": {**base, "trajectory": {"dtheta_deg": -90, "dT_s": 0.25, "w_ss": 1.5}},
    "missing robot": {"name": "x"},
    "bad sweep": {**base, "output": {"sample_dt_s": {"sweep": []}}},
}
opt = {"name": "o", "kind": "optimize", "base": "base/eq25_n1.yaml",
       "optimize": {"family": "split_cycle", "limits": {"theta_deg": [-90, 90], "thetadot_max_dps": 600}}}
man = {"name": "m", "kind": "maneuver", "base": "base/eq25_n1.yaml", "maneuver": {"heading_deg": 90}}
assert not list(exp_v.iter_errors(opt)), "the minimal optimize file must pass"
assert not list(exp_v.iter_errors(man)), "the minimal maneuver file must pass"
negatives.update({
    "optimize: unknown key": {**opt, "optimize": {**opt["optimize"], "islnds": 2}},
    "optimize: bad family": {**opt, "optimize": {**opt["optimize"], "family": "bezier"}},
    "optimize: no limits": {**opt, "optimize": {"family": "split_cycle"}},
    "optimize: one pareto point": {**opt, "optimize": {**opt["optimize"], "pareto_points": 1}},
    "optimize: theta_deg not an interval": {**opt, "optimize": {**opt["optimize"], "limits": {"theta_deg": [0], "thetadot_max_dps": 600}}},
    "optimize: a sweep": {**opt, "optimize": {**opt["optimize"], "islands": {"sweep": [1, 2]}}},
    "optimize: a robot key": {**opt, "robot": "paper"},
    "optimize: no base": {k: v for k, v in opt.items() if k != "base"},
    "maneuver: unknown key": {**man, "maneuver": {"heading_dg": 90}},
    "maneuver: section of the other kind": {**man, "kind": "optimize"},
})
for what, d in negatives.items():
    checked += 1
    if not list(exp_v.iter_errors(d)):
        failures.append(f"negative case accepted: {what}")
if list(robot_v.iter_errors({"quadruped": {}, "friction": {}, "gravity_mps2": 9.81, "tails": {}})) == []:
    failures.append("negative case accepted: robot file with empty sections")

for f in failures:
    print("FAIL", f)
print(f"{checked} documents checked, {len(failures)} failures")
sys.exit(1 if failures else 0)
