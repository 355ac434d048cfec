"""Do two builds give the same bits through the Python package, the FMU and the ROS node's
recording? Called by scripts/same_bits.sh when it is given two build directories; see there.

For each case (a coarse shipped scene and rule) and each build, with this interpreter:
- Python: rkforge.run(scene) from DIR/same_bits_python (a `pip install --target` of the
  build's wheel): the summary (less the wall and stage times) and the history's bytes;
- FMU: the scene packed by DIR/rkforge fmu, simulated by fmpy over the scene's end time at
  its history interval with the rule set through the FMU's parameter: every output of the old
  build's bytes against the new build's output of that name, or of its new name (the FMU's
  variables took the register's names in issue 34: `RENAMED`, the README's table); outputs
  only the new build has are counted, not compared;
- ROS: DIR/rkforge-ros --record, uncompressed: every message's topic, log time and bytes;
  and, apart, the embedded summary (less the wall times and the node's own figures).
Prints one line per case and front end; exit status 1 when any differs.

IGNORE_OUTPUTS="name ..." (as for scripts/same_bits.sh): the register's outputs of those names
that the new build adds are left out of the Python history and summaries, and the recordings'
`outputs` topic (which carries every output of the register) is left out of the messages.
"""
import hashlib
import json
import os
import pathlib
import subprocess
import sys
import tempfile

VOLATILE = ("wall_s", "stage_seconds", "ros")
IGNORED = set(os.environ.get("IGNORE_OUTPUTS", "").split())


def drop(v):
    """A summary less the IGNORED keys, at any depth."""
    if isinstance(v, dict):
        return {k: drop(x) for k, x in v.items() if k not in IGNORED}
    if isinstance(v, list):
        return [drop(x) for x in v]
    return v


# The FMU's earlier output names and their names now (README, "earlier name | name now").
RENAMED = [
    (r"(?<!early_return)\.force$", ".force_N"),
    (r"\.stroke$", ".stroke_m"),
    (r"^workpiece\.(radius|width|height)$", r"workpiece.\1_m"),
    (r"^energy\.(kinetic|plastic|tool_work)$", r"energy.\1_J"),
    (r"^thermal\.temperature_(min|max|mean)$", r"thermal.temperature_\1_c"),
    (r"^thermal\.(plastic_heat|friction_heat|heat_content|heat_to_tools|heat_to_surroundings)$",
     r"thermal.\1_J"),
    (r"^thermal\.heat_balance$", "thermal.heat_balance_rel"),
    (r"^(\w+)\.heat_flow$", r"thermal.\1.heat_flow_W"),
]


def new_name(old):
    """The name an FMU output of the old build has in the new one."""
    import re
    for pattern, replacement in RENAMED:
        name = re.sub(pattern, replacement, old)
        if name != old:
            return name
    return old


def digest(*parts):
    h = hashlib.sha256()
    for p in parts:
        h.update(p if isinstance(p, bytes) else str(p).encode())
    return h.hexdigest()[:16]


def python_run(build, scene, rule):
    code = (
        "import json, sys, rkforge\n"
        "s, h = rkforge.run(rkforge.Scene.from_file(sys.argv[1]), integration=sys.argv[2], check=False)\n"
        f"s = {{k: v for k, v in s.items() if k not in {VOLATILE!r}}}\n"
        f"h = h[[c for c in h.columns if c.rsplit('.', 1)[-1] not in {sorted(IGNORED)!r}]]\n"
        "sys.stdout.write(json.dumps(s, sort_keys=True) + '\\n')\n"
        "sys.stdout.write(','.join(h.columns) + '\\n' + h.to_numpy().tobytes().hex())\n"
    )
    env = dict(os.environ, PYTHONPATH=str(pathlib.Path(build) / "same_bits_python"))
    out = subprocess.run([sys.executable, "-c", code, str(scene), rule], env=env,
                         capture_output=True, text=True, check=True).stdout
    summary, history = out.split("\n", 1)
    return digest(json.dumps(drop(json.loads(summary)), sort_keys=True) + "\n" + history)


def fmu_run(build, scene, rule, work):
    """Each output's bytes, by name."""
    from fmpy import simulate_fmu
    import tomllib
    fmu = work / f"{pathlib.Path(build).name}-{scene.stem}.fmu"
    subprocess.run([str(pathlib.Path(build) / "rkforge"), "fmu", str(scene), "--out", str(fmu)],
                   check=True, capture_output=True)
    spec = tomllib.loads(scene.read_text())
    end = spec["time"]["end_s"]
    step = spec.get("output", {}).get("history_interval_s", end / 200)
    names = [n for n, c in fmu_variables(fmu) if c == "output"]
    rule_key = next(n for n, c in fmu_variables(fmu) if c == "parameter" and
                    n in ("integration", "discretization.integration"))
    result = simulate_fmu(str(fmu), stop_time=end, output_interval=step, step_size=step,
                          start_values={rule_key: rule}, output=names)
    return {n: result[n].tobytes() for n in names}


def fmu_compare(old, new):
    """Every old output against the new build's output of its new name: a digest of the
    pairs, and the names whose bytes differ or that the new build lacks."""
    pairs = [(n, new_name(n)) for n in old]
    differ = [f"{a} -> {b}" for a, b in pairs if new.get(b) != old[a]]
    added = len(set(new) - {b for _, b in pairs})
    return digest(*[old[a] for a, _ in pairs]) + f" ({len(pairs)} outputs, {added} new)", differ


def fmu_variables(fmu):
    from fmpy import read_model_description
    return [(v.name, v.causality) for v in read_model_description(str(fmu)).modelVariables]


def ros_run(build, scene, rule, work, domain):
    """The recording's messages and its embedded summary, each as a digest."""
    from mcap.reader import make_reader
    rec = work / f"{pathlib.Path(build).name}-{scene.stem}-{rule}.mcap"
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain))
    subprocess.run([str(pathlib.Path(build) / "rkforge-ros"), str(scene), "--record", str(rec),
                    "--record-compression", "none", "--set",
                    f"discretization.integration=\"{rule}\""],
                   env=env, check=True, capture_output=True, timeout=600)
    with open(rec, "rb") as f:
        messages = [(c.topic, m.log_time, bytes(m.data))
                    for _, c, m in make_reader(f).iter_messages()
                    if not (IGNORED and c.topic.endswith("/outputs"))]
    with open(rec, "rb") as f:
        meta = {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}
    summary = json.loads(meta["rkforge_summary"]["summary_json"])
    summary = drop({k: v for k, v in summary.items() if k not in VOLATILE})
    return (digest(*[t.encode() + str(lt).encode() + d for t, lt, d in messages])
            + f" ({len(messages)} messages)", digest(json.dumps(summary, sort_keys=True)))


def main(old, new, cases):
    failed = False
    with tempfile.TemporaryDirectory() as d:
        work = pathlib.Path(d)
        domain = 180
        for scene, rule in cases:
            scene = pathlib.Path(scene)
            results, fmus = {}, {}
            for b in (old, new):
                ros = ros_run(b, scene, rule, work, domain)
                results[b] = {"ros messages": ros[0], "ros summary": ros[1]}
                fmus[b] = fmu_run(b, scene, rule, work)
                if all((pathlib.Path(d) / "same_bits_python").is_dir() for d in (old, new)):
                    results[b]["python"] = python_run(b, scene, rule)
            tag = f"fmu {scene.stem} {rule}"
            summary, differ = fmu_compare(fmus[old], fmus[new])
            if differ:
                print(f"DIFFERENT: {tag}: {', '.join(differ)}")
                failed = True
            else:
                print(f"same bits: {tag} {summary}")
            for name in results[new]:
                a, b = results[old][name], results[new][name]
                tag = f"{name} {scene.stem} {rule}"
                if a == b:
                    print(f"same bits: {tag} {b}")
                else:
                    print(f"DIFFERENT: {tag}: {a} vs {b}")
                    failed = True
            domain += 1
    return 1 if failed else 0


if __name__ == "__main__":
    old, new, *rest = sys.argv[1:]
    sys.exit(main(old, new, [c.split(":") for c in rest]))
