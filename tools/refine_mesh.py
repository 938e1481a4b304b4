#!/usr/bin/env python3
"""Writes a model file with every shaft element of another split in two equal halves.

    python3 tools/refine_mesh.py models/dual_rotor.toml > examples/rotors/dual_rotor_fine.toml

The new node in the middle of element [a, b] gets id 100 + (its element's position in the
file); it joins a's rotor. Everything else (disks, bearings, supports, the thermal network)
is kept as written: those name nodes the split keeps. A tapered element is split at its
mid diameters. Only the `[[shafts]]` tables and the rotors' `nodes` lists change, edited
in the text so that its comments stay.
"""
import re
import sys
import tomllib


def main(path):
    text = open(path, encoding="utf-8").read()
    model = tomllib.loads(text)
    rotor_of = {n: r["id"] for r in model["rotors"] for n in r["nodes"]}
    added = {r["id"]: [] for r in model["rotors"]}
    # each [[shafts]] table as it is written, up to the next table header or blank line
    # before a comment
    pattern = re.compile(r"^\[\[shafts\]\]\n(?:(?!\[)[^\n]*\n)*?(?=\n|\[)", re.M)
    count = 0

    def split(m):
        nonlocal count
        block = m.group(0)
        s = model["shafts"][count]
        new = 100 + count
        count += 1
        a, b = s["nodes"]
        added[rotor_of[a]].append(new)
        halves = []
        for nodes in ([a, new], [new, b]):
            h = re.sub(r"^nodes = \[.*\]$", f"nodes = [{nodes[0]}, {nodes[1]}]", block, flags=re.M)
            h = re.sub(r"^length_m = .*$", f"length_m = {s['length_m'] / 2!r}", h, flags=re.M)
            halves.append(h)
        if "outer_diameter_end_m" in s or "inner_diameter_end_m" in s:
            raise SystemExit(f"{path}: tapered element {s['nodes']}: not supported")
        return halves[0] + "\n" + halves[1]

    text = pattern.sub(split, text)
    if count != len(model["shafts"]):
        raise SystemExit(f"{path}: found {count} of {len(model['shafts'])} [[shafts]] tables")
    for r in model["rotors"]:
        old = "nodes = [" + ", ".join(str(n) for n in r["nodes"]) + "]"
        new = "nodes = [" + ", ".join(str(n) for n in r["nodes"] + added[r["id"]]) + "]"
        if text.count(old) != 1:
            raise SystemExit(f"{path}: rotor {r['id']}: its nodes list is not written once")
        text = text.replace(old, new)
    name = model["name"]
    text = text.replace(f'name = "{name}"', f'name = "{name}_fine"', 1)
    header = (
        f"# {path} with every shaft element split in two (tools/refine_mesh.py): the same\n"
        f"# rotor on a mesh twice as fine, {len(rotor_of) + count} nodes instead of {len(rotor_of)}.\n"
        "# Generated; edit the original and run the tool again.\n"
    )
    sys.stdout.write(header + text)


if __name__ == "__main__":
    main(sys.argv[1])
