"""Runs the pikg-reflect command on header files: JSON on success, located
errors and the documented exit status otherwise.

usage: check_cli.py PIKG_REFLECT DATA_DIR RUNTIME_INCLUDE_DIR
"""
import json
import os
import subprocess
import sys
import tempfile

tool, data, runtime_include = sys.argv[1:4]
header = os.path.join(data, "particle.hpp")
includes = ["-I", os.path.join(data, "include"), f"-I{runtime_include}"]
failures = []


def run(*args):
    return subprocess.run([tool, *args], capture_output=True, text=True, timeout=60)


def check(condition, what, proc=None):
    if not condition:
        detail = f"\n  rc={proc.returncode}\n  stdout={proc.stdout}\n  stderr={proc.stderr}" if proc else ""
        failures.append(what + detail)


# Double precision by default, with the alias and the spelled-out template.
p = run(header, "--type", "galaxy::Body", "--type", "galaxy::Particle<float>", "--", "-std=c++20", *includes)
check(p.returncode == 0, "reflect particle.hpp", p)
if p.returncode == 0:
    doc = json.loads(p.stdout)
    check(doc["tool"] == "pikg-reflect" and doc["schema"] == 1, "JSON header", p)
    body, single = doc["records"]
    check(body["name"] == "galaxy::Particle<double>" and body["size"] == 40 and body["align"] == 8,
          f"galaxy::Body record: {body['name']} {body['size']} {body['align']}")
    fields = {f["name"]: f for f in body["fields"]}
    check(list(fields) == ["pos", "mass", "id"], f"field order {list(fields)}")
    check(fields["pos"]["kind"] == "vector" and fields["pos"]["count"] == 3 and fields["pos"]["scalar"] == "f64",
          f"pos {fields['pos']}")
    check([fields[n]["offset"] for n in ("pos", "mass", "id")] == [0, 24, 32], "double offsets")
    check(fields["mass"]["declared_type"] == "double" and fields["mass"]["type"] == "double", f"mass {fields['mass']}")
    check(fields["id"]["scalar"] == "s64", "id scalar")
    check(fields["pos"]["location"]["file"] == header and fields["pos"]["location"]["line"] == 12,
          f"pos location {fields['pos']['location']}")
    check(single["size"] == 24 and [f["offset"] for f in single["fields"]] == [0, 12, 16], f"float layout {single}")

# -D reaches the parser; -o writes a file.
with tempfile.TemporaryDirectory() as tmp:
    out = os.path.join(tmp, "body.json")
    p = run(header, "--type=galaxy::Body", "-o", out, "--compact", "--", "-DPIK_TEST_SINGLE", *includes)
    check(p.returncode == 0 and p.stdout == "", "-o with -D", p)
    if p.returncode == 0:
        with open(out) as f:
            rec = json.load(f)["records"][0]
        check(rec["name"] == "galaxy::Particle<float>" and rec["size"] == 24, f"-DPIK_TEST_SINGLE: {rec['name']}")

# An FDPS header that is not self-contained (PS:: types, particle_simulator.hpp not
# included): read with stand-ins and a note; --no-fdps-types refuses it; several headers
# (PIKG's --class-file EPI EPJ FORCE) in one call; --prelude includes a header first.
with tempfile.TemporaryDirectory() as tmp:
    def put(name, text):
        path = os.path.join(tmp, name)
        with open(path, "w") as f:
            f.write(text)
        return path
    user = put("user_defined.hpp", "struct FP { PS::F64 mass; PS::F64vec pos; };\n")
    p = run(user, "--type", "FP", "--compact")
    check(p.returncode == 0 and "note: the header uses FDPS/PIKG types" in p.stderr, "FDPS stand-ins", p)
    if p.returncode == 0:
        pos = json.loads(p.stdout)["records"][0]["fields"][1]
        check(pos["kind"] == "vector" and pos["offset"] == 8 and pos["count"] == 3, f"PS::F64vec as a vector: {pos}")
    p = run(user, "--type", "FP", "--no-fdps-types")
    check(p.returncode == 1 and "undeclared identifier 'PS'" in p.stderr, "--no-fdps-types", p)
    epi, epj, frc = (put(n + ".hpp", f"struct {n.upper()} {{ double pos[3]; float w; }};\n") for n in ("epi", "epj", "force"))
    p = run(epi, epj, frc, "--type", "EPI", "--type", "EPJ", "--type", "FORCE", "--compact")
    check(p.returncode == 0 and [r["name"] for r in json.loads(p.stdout or "{}").get("records", [])] == ["EPI", "EPJ", "FORCE"],
          "three headers", p)
    pre = put("types.hpp", "using real = double;\n")
    body = put("body.hpp", "struct B { real m; };\n")
    p = run(body, "--type", "B", "--prelude", pre, "--compact")
    check(p.returncode == 0 and p.stderr == "", "--prelude", p)
    p = run(body, os.path.join(tmp, "nope.hpp"), "--type", "B", "--prelude", pre)
    check(p.returncode == 1 and "nope.hpp: error: cannot read header: no such file" in p.stderr, "missing second header", p)
    p = run(body, "--type", "B", "--prelude")
    check(p.returncode == 2 and "--prelude needs a header file name" in p.stderr, "--prelude without a value", p)

# Unknown type: exit 1, the header named, a suggestion.
p = run(header, "--type", "galaxy::Bodyy", "--", *includes)
check(p.returncode == 1 and "type 'galaxy::Bodyy' not found in " + header in p.stderr
      and "did you mean" in p.stderr and p.stdout == "", "unknown type", p)

# A header that does not compile: file:line:col of the error.
broken = os.path.join(data, "broken.hpp")
p = run(broken, "--type", "Body")
check(p.returncode == 1 and f"{broken}:4:3: error: unknown type name 'vec3'" in p.stderr, "broken header", p)

# A missing include directory is a header error too.
p = run(header, "--type", "galaxy::Body")
check(p.returncode == 1 and "'pik/Vec.hpp' file not found" in p.stderr, "missing -I", p)

# Usage errors: exit 2.
for args in ([], [header], ["--bogus", header, "--type", "X"], [header, "--type"]):
    p = run(*args)
    check(p.returncode == 2 and "usage:" in p.stderr, f"usage error {args}", p)
p = run(os.path.join(data, "no_such.hpp"), "--type", "X")
check(p.returncode == 1 and "no such file" in p.stderr, "missing header", p)
p = run(data, "--type", "X")
check(p.returncode == 1 and "is a directory" in p.stderr, "directory as header", p)

for f in failures:
    print("FAIL:", f)
print(f"{'FAILED' if failures else 'OK'}: check_cli.py")
sys.exit(1 if failures else 0)
