#!/usr/bin/env python3
"""Whole runs compared with what they wrote before a change (tests/data/regression/*.json).

  regression.py record BIN_DIR GOLDEN_DIR   runs every case and writes its record
  regression.py check  BIN_DIR GOLDEN_DIR   runs every case and compares it with its record

A record holds, for every file a run writes (frames NNN.obj / NNN.vtu, frames.pvd, stats.csv), its
SHA-256 and a digest of the numbers in it (of a .vtu frame: the values of its data arrays, binary or text), and the run's stats.json (or lab.json) without the fields
that vary from run to run (times, memory, paths). On a machine like the one that recorded it (same CPU
model and flags, same compiler: the "signature"), a run must be bit-identical: every file's SHA-256 and
every stats value equal. Elsewhere floating-point results may differ in the last bits (-march=native,
OpenBLAS kernels chosen per CPU) and grow through Newton's tolerance, so the numbers are compared to a
relative 1e-5 and iteration counts are not compared (nor stats.csv, whose digest includes them: its values
are stats.json's, compared without the counts); the output says which comparison was made
(SNH_REGRESSION_TOLERANT=1 asks for that comparison anywhere; SNH_REGRESSION_ONLY=REGEX picks cases).
"""
import hashlib
import json
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# name: the command, with {snh}, {tetcli}, {hexcli}, {root} and {out} substituted.
CASES = {
    "tetcli_10": ["{tetcli}", "10", "stable_neo_hookean", "1.0", "10.0", "{out}"],
    "hexcli_10": ["{hexcli}", "10", "stable_neo_hookean", "1.0", "10.0", "{out}"],
    "tetcli_6_neo_hookean": ["{tetcli}", "6", "neo_hookean", "1.0", "10.0", "{out}"],
    "stretch_hex_6_pcg": ["{snh}", "stretch", "--element", "hex", "--res", "6", "--solver", "pcg", "--out", "{out}"],
    "stretch_tet_4_ldlt_refactorize_projected": ["{snh}", "stretch", "--res", "4", "--solver", "ldlt", "--refactorize",
                                                 "--projected-only", "--tet-split", "mirrored", "--out", "{out}"],
    "stretch_bunny_x": ["{snh}", "stretch", "--mesh", "{root}/data/bunny.msh", "--axis", "x", "--steps", "4",
                        "--stretch", "1.2", "--youngs", "1000", "--poisson", "0.45", "--reparametrize", "--out", "{out}"],
    "lab_quick": ["{snh}", "lab", "--quick", "--out", "{out}"],
}
SCENES = sorted(f[:-5] for f in os.listdir(os.path.join(ROOT, "scenes")) if f.endswith(".json"))
for _scene in SCENES:
    CASES["scene_" + _scene] = ["{snh}", "run", "{root}/scenes/" + _scene + ".json", "--out", "{out}"]

# Fields of stats.json / lab.json that differ between identical runs, or name paths.
VARYING = {"wall_seconds", "assembly_seconds", "solve_seconds", "contact_seconds", "total_seconds", "peak_memory_mib", "command_line",
           "scene", "mesh_file", "model"}
CSV_VARYING = {"wall_seconds", "assembly_seconds", "solve_seconds", "contact_seconds"}
# Compared only on a machine like the recording one: counts that a last-bit difference may change.
COUNTS = {"newton_iterations", "newton_step", "line_search_steps", "linear_iterations", "factorizations", "true_hessian_steps",
          "residual", "residual_history", "ccd_calls", "ccd_tests"}
NUMBER = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
RTOL = 1e-5


def signature():
    """CPU model and flags, and the compiler: what decides whether results can be bit-identical."""
    model, flags = "", ""
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name") and not model:
                model = line.split(":", 1)[1].strip()
            if line.startswith("flags") and not flags:
                flags = " ".join(sorted(line.split(":", 1)[1].split()))
    try:
        cxx = subprocess.run(["g++", "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        cxx = "?"
    return f"{model} | {hashlib.sha256(flags.encode()).hexdigest()[:16]} | {cxx}"


# VTK's value types as struct format characters (little-endian).
VTK_TYPES = {"Float64": "d", "Float32": "f", "Int64": "q", "UInt64": "Q", "Int32": "i", "UInt32": "I", "Int16": "h",
             "UInt16": "H", "Int8": "b", "UInt8": "B"}


def vtu_arrays(data):
    """(tag, values) of every DataArray of a .vtu file in document order: ASCII, or appended raw (as snh
    writes its frames: little-endian, uncompressed, UInt32 or UInt64 length headers)."""
    ad = data.find(b"<AppendedData")
    xml = data if ad < 0 else data[:ad]
    if ad >= 0 and b'encoding="raw"' not in data[ad:data.index(b">", ad)]:
        raise ValueError("appended data that is not raw")
    appended = ad + data[ad:].index(b"_") + 1 if ad >= 0 else -1
    header = "Q" if b'header_type="UInt64"' in xml else "I"
    out = []
    for m in re.finditer(rb"<DataArray\b[^>]*>", xml):
        tag = m.group().decode()
        if 'format="appended"' in tag:
            at = appended + int(re.search(r'offset="(\d+)"', tag).group(1))
            (length,) = struct.unpack_from("<" + header, data, at)
            kind = VTK_TYPES[re.search(r'type="(\w+)"', tag).group(1)]
            count = length // struct.calcsize(kind)
            values = struct.unpack_from(f"<{count}{kind}", data, at + struct.calcsize(header))
        else:
            end = xml.index(b"</DataArray>", m.end())
            values = [float(v) for v in NUMBER.findall(xml[m.end():end])]
        out.append((tag, [float(v) for v in values]))
    return out


def digest(data, values=None):
    """Count, sum, sum of magnitudes and a position-weighted sum of the numbers in a text file (or of
    `values`)."""
    n, s, a, w = 0, 0.0, 0.0, 0.0
    for v in values if values is not None else (float(m.group()) for m in NUMBER.finditer(data)):
        if not math.isfinite(v):
            continue
        n += 1
        s += v
        a += abs(v)
        w += (n % 13 + 1) * v
    return {"count": n, "sum": s, "abs": a, "weighted": w}


def strip(value):
    if isinstance(value, dict):
        return {k: strip(v) for k, v in sorted(value.items()) if k not in VARYING}
    if isinstance(value, list):
        return [strip(v) for v in value]
    return value


def csv_without_times(text):
    lines = text.splitlines()
    if not lines:
        return ""
    head = lines[0].split(",")
    keep = [i for i, h in enumerate(head) if h not in CSV_VARYING]
    return "\n".join(",".join(row.split(",")[i] for i in keep) for row in lines) + "\n"


def run_case(name, argv, bins, out):
    subst = dict(bins, root=ROOT, out=out)
    cmd = [a.format(**subst) for a in argv]
    env = dict(os.environ, OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "2"))
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if r.returncode != 0:
        raise SystemExit(f"{name}: exit code {r.returncode}: {(r.stdout + r.stderr).strip().splitlines()[-3:]}")
    record = {"command": argv, "files": {}}
    for f in sorted(os.listdir(out)):
        p = os.path.join(out, f)
        if not os.path.isfile(p):
            continue
        if re.fullmatch(r"\d+\.(obj|vtu)|frames\.pvd", f):
            data = open(p, "rb").read()
            values = [v for _, a in vtu_arrays(data) for v in a] if f.endswith(".vtu") else None
            record["files"][f] = {"sha256": hashlib.sha256(data).hexdigest(), **digest(data, values)}
        elif f == "stats.csv":
            data = csv_without_times(open(p).read()).encode()
            record["files"][f] = {"sha256": hashlib.sha256(data).hexdigest(), **digest(data)}
    for f in ("stats.json", "lab.json"):
        if os.path.exists(os.path.join(out, f)):
            with open(os.path.join(out, f)) as fh:
                record[f] = strip(json.load(fh))
    return record


def close(a, b, scale):
    return abs(a - b) <= RTOL * max(abs(a), abs(b), scale)


def compare_values(path, old, new, exact, problems, scale=1e-12):
    if isinstance(old, dict):
        if not isinstance(new, dict):
            problems.append(f"{path}: was an object")
            return
        for k, v in old.items():
            if k not in new:
                problems.append(f"{path}.{k}: missing")
            elif exact or k not in COUNTS:
                compare_values(f"{path}.{k}", v, new[k], exact, problems)
    elif isinstance(old, list):
        if not isinstance(new, list) or len(old) != len(new):
            problems.append(f"{path}: length {len(old)} became {len(new) if isinstance(new, list) else new!r}")
            return
        for i, (o, n) in enumerate(zip(old, new)):
            compare_values(f"{path}[{i}]", o, n, exact, problems)
    elif exact:
        if old != new:
            problems.append(f"{path}: {old!r} became {new!r}")
    elif isinstance(old, float) and isinstance(new, (int, float)):
        if not close(old, new, scale):
            problems.append(f"{path}: {old!r} became {new!r}")
    elif old != new and not (isinstance(old, int) and isinstance(new, (int, float)) and close(old, new, scale)):
        problems.append(f"{path}: {old!r} became {new!r}")


def compare(name, old, new, exact):
    problems = []
    for f, o in old["files"].items():
        n = new["files"].get(f)
        if n is None:
            problems.append(f"{f}: not written")
        elif exact and o["sha256"] != n["sha256"]:
            problems.append(f"{f}: not bit-identical")
        elif not exact and f == "stats.csv":
            continue  # its numbers include the iteration counts; its values are compared in stats.json
        elif not exact:
            if o["count"] != n["count"]:
                problems.append(f"{f}: {o['count']} numbers became {n['count']}")
            for k in ("sum", "weighted"):
                if not close(o[k], n[k], o["abs"]):
                    problems.append(f"{f}: {k} of its numbers {o[k]!r} became {n[k]!r}")
    for f in new["files"]:
        if f not in old["files"]:
            problems.append(f"{f}: written now, not before")
    for f in ("stats.json", "lab.json"):
        if f in old:
            compare_values(f, old[f], new.get(f), exact, problems)
    return [f"{name}: {p}" for p in problems]


def main():
    if len(sys.argv) != 4 or sys.argv[1] not in ("record", "check"):
        print(__doc__)
        return 2
    mode, bin_dir, golden = sys.argv[1:]
    bins = {b: os.path.join(bin_dir, b) for b in ("snh", "tetcli", "hexcli")}
    only = os.environ.get("SNH_REGRESSION_ONLY")
    names = [n for n in CASES if not only or re.search(only, n)]
    sig = signature()
    work = tempfile.mkdtemp(prefix="snh-regression-")
    failures = []
    try:
        for name in names:
            out = os.path.join(work, name)
            record = run_case(name, CASES[name], bins, out)
            path = os.path.join(golden, name + ".json")
            if mode == "record":
                record["signature"] = sig
                os.makedirs(golden, exist_ok=True)
                with open(path, "w") as fh:
                    json.dump(record, fh, indent=1, sort_keys=True)
                    fh.write("\n")
                print(f"recorded {name}")
                continue
            with open(path) as fh:
                old = json.load(fh)
            exact = old.get("signature") == sig and not os.environ.get("SNH_REGRESSION_TOLERANT")
            problems = compare(name, old, record, exact)
            failures += problems
            how = "bit-identical" if exact else f"to a relative {RTOL:g} (recorded on {old.get('signature')}, this is {sig})"
            print(f"{'ok  ' if not problems else 'FAIL'} {name}: {len(record['files'])} files, compared {how}")
            for p in problems[:10]:
                print("     " + p)
            shutil.rmtree(out, ignore_errors=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    if mode == "check":
        print(f"{len(names) - len({f.split(':')[0] for f in failures})} of {len(names)} runs as recorded")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
