"""Reference numbers from ROSS (ross-rotordynamics, https://github.com/petrobras/ross) for
tests/ross_linear.rs: a rotor with cross-coupled and speed-dependent bearings, written
once as a tmrotor model file and once as a ROSS rotor, and ROSS's damped eigenvalues and
unbalance responses at a few speeds.

Run (outside CI; ROSS is not a test dependency):

    python3 -m venv /tmp/ross && /tmp/ross/bin/pip install ross-rotordynamics "plotly<6"
    /tmp/ross/bin/python tools/ross_reference.py tests/fixtures/ross

It writes, per case, `<case>.toml` (the tmrotor model) and `<case>.json` (ROSS's numbers,
with the ROSS version).
"""

import json
import sys
from pathlib import Path

import numpy as np
import ross as rs

STEEL = dict(rho=7810.0, E=211e9, Poisson=0.3)
N_EL = 6
L_EL = 0.1
SECTIONS = [(0.0, 0.05)] * 2 + [(0.02, 0.06)] * 2 + [(0.0, 0.05)] * 2  # (id, od)
DISKS = [(2, 10.0, 0.05, 0.1), (4, 6.0, 0.03, 0.06)]  # (node, m, Id, Ip)
SPEEDS = [0.0, 300.0, 800.0]

# Bearing coefficients: cross-coupled constants at node 0, a speed table at node 6.
CONST = dict(kxx=1.0e7, kyy=1.5e7, kxy=2.0e6, kyx=-3.0e6, cxx=500.0, cyy=700.0, cxy=50.0, cyx=-40.0)
# Two speeds: ROSS interpolates two-point tables linearly (scipy interp1d, kind 1), as
# tmrotor does; with three it fits a parabola and with more a smoothing spline, so the
# comparison stays at two points and at speeds inside the table.
TABLE_SPEEDS = [200.0, 1000.0]
TABLE = dict(
    kxx=[2.0e7, 3.0e7],
    kyy=[2.5e7, 3.2e7],
    kxy=[1.0e6, 9.0e6],
    kyx=[-2.0e6, -1.1e7],
    cxx=[800.0, 1000.0],
    cyy=[850.0, 1100.0],
    cxy=[10.0, 60.0],
    cyx=[-5.0, -50.0],
)
UNBALANCE = dict(node=2, magnitude=1e-4, phase=0.0)  # kg·m at the first disk
FREQS = [100.0, 250.0, 600.0]


# The tapered case: the same rotor with elements 2 and 5 conical (outer 0.05 → 0.06 and
# 0.06 → 0.05 m), meshed into `TAPER_SPLIT` elements each so that both codes converge.
TAPERS = {1: (0.0, 0.05, 0.0, 0.06), 4: (0.0, 0.06, 0.0, 0.05)}  # element: idl, odl, idr, odr


def tapered_sections(split):
    """Elements as (length, idl, odl, idr, odr), the conical ones cut into `split` pieces."""
    out = []
    for k, (i, o) in enumerate(SECTIONS):
        if k in TAPERS:
            idl, odl, idr, odr = TAPERS[k]
            for j in range(split):
                f0, f1 = j / split, (j + 1) / split
                out.append((L_EL / split, idl + f0 * (idr - idl), odl + f0 * (odr - odl),
                            idl + f1 * (idr - idl), odl + f1 * (odr - odl)))
        else:
            out.append((L_EL, i, o, i, o))
    return out


def ross_rotor(with_table: bool):
    steel = rs.Material(name="steel", **STEEL)
    shafts = [
        rs.ShaftElement(L=L_EL, idl=i, odl=o, material=steel, shear_effects=True,
                        rotary_inertia=True, gyroscopic=True, shear_method_calc="cowper")
        for (i, o) in SECTIONS
    ]
    disks = [rs.DiskElement(n=n, m=m, Id=Id, Ip=Ip) for (n, m, Id, Ip) in DISKS]
    b0 = rs.BearingElement(n=0, **CONST)
    if with_table:
        b6 = rs.BearingElement(n=N_EL, frequency=TABLE_SPEEDS, **TABLE)
    else:
        b6 = rs.BearingElement(n=N_EL, kxx=2.0e7, kyy=2.5e7, cxx=800.0, cyy=850.0)
    return rs.Rotor(shafts, disks, [b0, b6])


def model_toml(name: str, with_table: bool) -> str:
    lines = [
        f'name = "{name}"',
        'description = "Reference rotor of tools/ross_reference.py: checked against ROSS"',
        "",
        "[gravity]",
        "enabled = false",
        "",
        "[[materials]]",
        'id = "steel"',
        f"youngs_modulus_pa = {STEEL['E']:e}",
        f"poisson_ratio = {STEEL['Poisson']}",
        f"density_kg_m3 = {STEEL['rho']}",
        "",
        "[[rotors]]",
        'id = "rotor"',
        'speed_ratio = "1"',
        f"nodes = {list(range(1, N_EL + 2))}",
    ]
    for k, (i, o) in enumerate(SECTIONS):
        lines += ["", "[[shafts]]", f"nodes = [{k + 1}, {k + 2}]", f"length_m = {L_EL}",
                  f"inner_diameter_m = {i}", f"outer_diameter_m = {o}", 'material = "steel"']
    for j, (n, m, Id, Ip) in enumerate(DISKS):
        lines += ["", "[[disks]]", f'id = "disk{j + 1}"', f"node = {n + 1}", f"mass_kg = {m}",
                  f"polar_inertia_kg_m2 = {Ip}", f"diametral_inertia_kg_m2 = {Id}"]
        if n == UNBALANCE["node"]:
            lines += [f"eccentricity_m = {UNBALANCE['magnitude'] / m:.17g}",
                      f"phase_deg = {UNBALANCE['phase']}"]
    c = CONST
    lines += ["", "[[supports]]", 'id = "left"', "node = 1",
              f"stiffness_xx_n_m = {c['kxx']:e}", f"stiffness_yy_n_m = {c['kyy']:e}",
              f"stiffness_xy_n_m = {c['kxy']:e}", f"stiffness_yx_n_m = {c['kyx']:e}",
              f"damping_xx_n_s_m = {c['cxx']}", f"damping_yy_n_s_m = {c['cyy']}",
              f"damping_xy_n_s_m = {c['cxy']}", f"damping_yx_n_s_m = {c['cyx']}"]
    lines += ["", "[[supports]]", 'id = "right"', f"node = {N_EL + 1}"]
    if with_table:
        lines += ["", "[supports.table]", f"speeds_rad_s = {TABLE_SPEEDS}"]
        unit = {"k": "n_m", "c": "n_s_m"}
        for key, vals in TABLE.items():
            lines.append(f"{key}_{unit[key[0]]} = [{', '.join(f'{v:e}' for v in vals)}]")
    else:
        lines += ["stiffness_xx_n_m = 2.0e7", "stiffness_yy_n_m = 2.5e7",
                  "damping_xx_n_s_m = 800.0", "damping_yy_n_s_m = 850.0"]
    return "\n".join(lines) + "\n"


def tapered_toml(name, elements, node_of):
    """The tapered rotor as a tmrotor model (conical elements by their end diameters)."""
    n_nodes = len(elements) + 1
    lines = [f'name = "{name}"', 'description = "tools/ross_reference.py: conical elements"', "",
             "[gravity]", "enabled = false", "", "[[materials]]", 'id = "steel"',
             f"youngs_modulus_pa = {STEEL['E']:e}", f"poisson_ratio = {STEEL['Poisson']}",
             f"density_kg_m3 = {STEEL['rho']}", "", "[[rotors]]", 'id = "rotor"',
             'speed_ratio = "1"', f"nodes = {list(range(1, n_nodes + 1))}"]
    for k, (le, a, b, c, d) in enumerate(elements):
        lines += ["", "[[shafts]]", f"nodes = [{k + 1}, {k + 2}]", f"length_m = {le!r}",
                  f"inner_diameter_m = {a!r}", f"outer_diameter_m = {b!r}"]
        if (c, d) != (a, b):
            lines += [f"inner_diameter_end_m = {c!r}", f"outer_diameter_end_m = {d!r}"]
        lines.append('material = "steel"')
    for j, (nd, m, Id, Ip) in enumerate(DISKS):
        lines += ["", "[[disks]]", f'id = "disk{j + 1}"', f"node = {node_of[nd] + 1}",
                  f"mass_kg = {m}", f"polar_inertia_kg_m2 = {Ip}", f"diametral_inertia_kg_m2 = {Id}"]
    c = CONST
    lines += ["", "[[supports]]", 'id = "left"', "node = 1",
              f"stiffness_xx_n_m = {c['kxx']:e}", f"stiffness_yy_n_m = {c['kyy']:e}",
              f"stiffness_xy_n_m = {c['kxy']:e}", f"stiffness_yx_n_m = {c['kyx']:e}",
              f"damping_xx_n_s_m = {c['cxx']}", f"damping_yy_n_s_m = {c['cyy']}",
              f"damping_xy_n_s_m = {c['cxy']}", f"damping_yx_n_s_m = {c['cyx']}",
              "", "[[supports]]", 'id = "right"', f"node = {node_of[N_EL] + 1}",
              "stiffness_xx_n_m = 2.0e7", "stiffness_yy_n_m = 2.5e7",
              "damping_xx_n_s_m = 800.0", "damping_yy_n_s_m = 850.0"]
    return "\n".join(lines) + "\n"


def lateral_eigenvalues(rotor, speed, count):
    """ROSS's eigenvalues with positive imaginary part, lowest |λ| first. ROSS's nodes
    carry axial and torsional DoFs too; the test matches each tmrotor mode to the nearest
    of these, so the list is kept longer than the test needs."""
    modal = rotor.run_modal(speed=speed, num_modes=4 * count)
    ev = np.asarray(modal.evalues)
    ev = ev[ev.imag > 1e-6]
    ev = ev[np.argsort(np.abs(ev))]
    return [[float(z.real), float(z.imag)] for z in ev[: 3 * count]]


def unbalance(rotor, freqs):
    resp = rotor.run_unbalance_response(
        node=[UNBALANCE["node"]], unbalance_magnitude=[UNBALANCE["magnitude"]],
        unbalance_phase=[UNBALANCE["phase"]], frequency=freqs)
    out = []
    ndof = rotor.number_dof
    for k, w in enumerate(freqs):
        row = {"speed_rad_s": w, "nodes": []}
        for node in range(N_EL + 1):
            fx = complex(resp.forced_resp[ndof * node + 0, k])
            fy = complex(resp.forced_resp[ndof * node + 1, k])
            row["nodes"].append({"x": [fx.real, fx.imag], "y": [fy.real, fy.imag]})
        out.append(row)
    return out


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "tests/fixtures/ross")
    out.mkdir(parents=True, exist_ok=True)
    for case, with_table in [("cross_coupled", False), ("speed_table", True)]:
        rotor = ross_rotor(with_table)
        speeds = [200.0, 500.0, 800.0, 1000.0] if with_table else SPEEDS
        ref = {
            "ross_version": rs.__version__,
            "dof_per_node": rotor.number_dof,
            "modes": [{"speed_rad_s": w, "eigenvalues": lateral_eigenvalues(rotor, w, 6)}
                      for w in speeds],
            "unbalance": {"node": UNBALANCE["node"] + 1, "magnitude_kg_m": UNBALANCE["magnitude"],
                          "response": unbalance(rotor, [300.0, 500.0, 900.0] if with_table else FREQS)},
        }
        (out / f"{case}.toml").write_text(model_toml(f"ross_{case}", with_table))
        (out / f"{case}.json").write_text(json.dumps(ref, indent=1) + "\n")
        print(f"{case}: {len(ref['modes'])} speeds")
    for split in (1, 4):
        steel = rs.Material(name="steel", **STEEL)
        elements = tapered_sections(split)
        shafts = [rs.ShaftElement(L=le, idl=a, odl=b, idr=c, odr=d, material=steel,
                                  shear_effects=True, rotary_inertia=True, gyroscopic=True,
                                  shear_method_calc="cowper") for (le, a, b, c, d) in elements]
        # disk nodes move with the split: node numbers of the original nodes
        node_of = []
        n = 0
        for k in range(N_EL + 1):
            node_of.append(n)
            if k < N_EL:
                n += split if k in TAPERS else 1
        disks = [rs.DiskElement(n=node_of[nd], m=m, Id=Id, Ip=Ip) for (nd, m, Id, Ip) in DISKS]
        bearings = [rs.BearingElement(n=0, **CONST),
                    rs.BearingElement(n=node_of[N_EL], kxx=2.0e7, kyy=2.5e7, cxx=800.0, cyy=850.0)]
        rotor = rs.Rotor(shafts, disks, bearings)
        case = f"tapered_{split}"
        ref = {"ross_version": rs.__version__, "dof_per_node": rotor.number_dof,
               "modes": [{"speed_rad_s": w, "eigenvalues": lateral_eigenvalues(rotor, w, 6)}
                         for w in SPEEDS]}
        (out / f"{case}.json").write_text(json.dumps(ref, indent=1) + "\n")
        (out / f"{case}.toml").write_text(tapered_toml(case, elements, node_of))
        print(f"{case}: {len(elements)} elements")


if __name__ == "__main__":
    main()
