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
