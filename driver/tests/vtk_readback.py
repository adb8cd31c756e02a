"""Read every VTK output of an lbdem run directory back with the real VTK library and check it.

Usage: python3 vtk_readback.py RUN_DIR

Run by driver/tests/vtk_readback.rs on the run directories of tiny scenes of every kind that writes snapshots
(fracture, dry, coupled_demo, terminal_velocity, consolidation, terzaghi, and the kinds whose grains are held
fixed: pressure_diffusion, porous_flow and cylinder_array, the sweeps with one group of series per case,
`particles_caseK.pvd`, `lattice_caseK.pvd`; see docs/outputs.md). For every
`.pvd` collection: the listed files exist and are read by VTK's XML readers (the readers ParaView uses), times
are finite and increasing and equal to each file's TIME field data; every array has its documented name,
component count and tuple count (points or cells) and finite values, and every physical array names its unit.
Then values against the run's own tables: grains, bonds and lattice nodes counted as in summary.json (no bond
series without bonds, no lattice without a fluid), recorded break times and modes equal to breaks.csv /
broken_bonds.csv, the kinetic energy of the last grain snapshot against history.csv (fracture) or series.csv
(coupled_demo, with the grain momentum), the disc's final velocity against summary.json (terminal_velocity),
the grains on the t = 0 lattice, the lattice's centre-line pressure and maximum fluid speed of the last snapshot
against centerline_pressure.csv and history.csv (fracture), grains held fixed at rest with mass -1, the t = 0
lattice's covered area against the grains' (sum of eps h^2 = sum of pi a b f^2), the snapshot times against
profiles.csv and the lattice's pressure against the initial overpressure (pressure_diffusion) or the imposed
pressure drop at the Zou-He sides (porous_flow), and the shape tensor drawn by VTK's tensor glyph
filter (what ParaView's Tensor Glyph runs) against the true ellipse of a few grains. Exits non-zero with a message on the
first failure; prints one line per checked file otherwise.
"""
import csv
import json
import math
import os
import re
import sys
import xml.etree.ElementTree as ET

import vtk
from vtk.util.numpy_support import vtk_to_numpy
import numpy as np  # installed with vtk (through its matplotlib dependency)

# Array name -> components, for each series (docs/outputs.md lists the same).
PARTICLE_ARRAYS = {
    "speed": 1, "velocity": 3, "shape_tensor": 9, "id": 1, "angular_velocity": 1, "orientation": 1,
    "major_axis": 3, "semi_axes": 3, "glyph_scale": 3, "mass": 1, "moment_of_inertia": 1, "contact_force": 3,
    "wall_force": 3, "contact_count": 1,
    "bonds": 1, "broken_bond_fraction": 1,
}
PARTICLE_FLUID_ARRAYS = {"fluid_force": 3, "fluid_torque": 1}
BOND_ARRAYS = {
    "intact": 1, "id": 1, "pair": 2, "break_mode": 1, "break_time": 1, "normal_force": 1,
    "shear_force": 1, "stretch": 1, "strength_ratio": 1,
}
LATTICE_ARRAYS = {"pressure": 1, "velocity": 3, "solid_fraction": 1, "node_kind": 1}
# Arrays without a unit (indices, counts, codes).
UNITLESS = {"id", "contact_count", "bonds", "intact", "pair", "break_mode", "node_kind"}


def fail(msg):
    print(f"vtk_readback: FAIL: {msg}", file=sys.stderr)
    sys.exit(1)


def check(cond, msg):
    if not cond:
        fail(msg)


def arr(data, name):
    a = data.GetArray(name)
    check(a is not None, f"array {name} missing")
    return vtk_to_numpy(a)


def read(path):
    if path.endswith(".vtp"):
        r = vtk.vtkXMLPolyDataReader()
    elif path.endswith(".vti"):
        r = vtk.vtkXMLImageDataReader()
    else:
        fail(f"{path}: unexpected extension")
    check(r.CanReadFile(path), f"{path}: VTK cannot read it")
    r.SetFileName(path)
    r.Update()
    check(r.GetErrorCode() == 0, f"{path}: VTK read error {r.GetErrorCode()}")
    return r.GetOutput()


def field_strings(obj, name):
    a = obj.GetFieldData().GetAbstractArray(name)
    check(a is not None, f"field data {name} missing")
    return [a.GetValue(i) for i in range(a.GetNumberOfValues())]


def check_arrays(path, data, expected, tuples, units):
    names = [data.GetArrayName(i) for i in range(data.GetNumberOfArrays())]
    check(sorted(names) == sorted(expected), f"{path}: arrays {sorted(names)}, expected {sorted(expected)}")
    for name, comps in expected.items():
        a = data.GetArray(name)
        check(a.GetNumberOfComponents() == comps, f"{path}: {name} has {a.GetNumberOfComponents()} components, expected {comps}")
        check(a.GetNumberOfTuples() == tuples, f"{path}: {name} has {a.GetNumberOfTuples()} tuples, expected {tuples}")
        check(np.all(np.isfinite(vtk_to_numpy(a).astype(float))), f"{path}: {name} holds non-finite values")
        if name not in UNITLESS:
            check(name in units and units[name], f"{path}: no unit named for {name} (units: {units})")


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def collection(run, series):
    path = os.path.join(run, f"{series}.pvd")
    check(os.path.exists(path), f"{path} missing")
    root = ET.parse(path).getroot()
    check(root.get("type") == "Collection", f"{path}: not a Collection")
    entries = [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]
    check(len(entries) >= 2, f"{path}: {len(entries)} snapshots")
    times = [t for t, _ in entries]
    check(all(math.isfinite(t) for t in times), f"{path}: non-finite times")
    check(all(b > a for a, b in zip(times, times[1:])), f"{path}: times not increasing: {times}")
    on_disk = sorted(f for f in os.listdir(run) if f.startswith(series + "_") and f.endswith((".vtp", ".vti")))
    check(sorted(f for _, f in entries) == on_disk, f"{path} lists {[f for _, f in entries]}, on disk {on_disk}")
    out = []
    for t, f in entries:
        full = os.path.join(run, f)
        obj = read(full)
        time = obj.GetFieldData().GetArray("TIME")
        check(time is not None and time.GetValue(0) == t, f"{full}: TIME field data differs from the .pvd time {t}")
        units = dict(s.split("=", 1) for s in field_strings(obj, "units"))
        out.append((t, full, obj, units))
    return out


def ellipse_half_extent(a, b, theta):
    c, s = math.cos(theta), math.sin(theta)
    return math.sqrt((a * c) ** 2 + (b * s) ** 2), math.sqrt((a * s) ** 2 + (b * c) ** 2)


def check_glyphs(path, grains):
    """ParaView's Tensor Glyph (vtkTensorGlyph, sphere of diameter 1, scale factor 1, eigenvalues extracted)
    must draw each grain's true ellipse: its x and y extents are those of the ellipse."""
    pd = grains.GetPointData()
    tensor = pd.GetArray("shape_tensor")
    axes = arr(pd, "semi_axes")
    theta = arr(pd, "orientation")
    for i in range(min(5, grains.GetNumberOfPoints())):
        one = vtk.vtkPolyData()
        pts = vtk.vtkPoints()
        pts.InsertNextPoint(grains.GetPoint(i))
        one.SetPoints(pts)
        t = vtk.vtkDoubleArray()
        t.SetNumberOfComponents(9)
        t.InsertNextTuple(tensor.GetTuple(i))
        one.GetPointData().SetTensors(t)
        sphere = vtk.vtkSphereSource()
        sphere.SetThetaResolution(256)
        sphere.SetPhiResolution(128)
        g = vtk.vtkTensorGlyph()
        g.SetInputData(one)
        g.SetSourceConnection(sphere.GetOutputPort())
        g.Update()
        b = g.GetOutput().GetBounds()
        hx, hy = ellipse_half_extent(axes[i][0], axes[i][1], theta[i])
        x, y, _ = grains.GetPoint(i)
        # The tessellated sphere lies inside the true one: its extent is short by at most 1 - cos(pi/128) of a
        # radius (128 segments per half circle) ~ 3e-4; 1e-3 of the semi-major axis bounds that.
        tol = 1e-3 * axes[i][0]
        for got, want in [(b[0], x - hx), (b[1], x + hx), (b[2], y - hy), (b[3], y + hy)]:
            check(abs(got - want) <= tol, f"{path}: tensor glyph of grain {i} spans {b[:4]}, the ellipse {x - hx, x + hx, y - hy, y + hy}")


def expectations(kind, summary):
    """(grains, bonds or None, lattice nodes (nx, ny) or None) of a run of `kind`, from its summary."""
    res, scene = summary["results"], summary["scene"]
    if kind == "fracture":
        fluid = res.get("fluid")
        return res["packing"]["particles"], res["total_bonds"], tuple(fluid["nodes"]) if fluid else None
    if kind == "dry":
        return res["particles"], res["bonds"], None
    if kind == "coupled_demo":
        d = scene["demo"]
        return d["discs"], None, (d["nx"], d["ny"])
    if kind == "terminal_velocity":
        return 1, None, (res["cell"], res["cell"])
    if kind == "consolidation":
        c = scene["consolidation"]
        return c["columns"] * c["rows"], None, tuple(res["nodes"])
    if kind == "terzaghi":
        return res["grains"], None, tuple(res["nodes"])
    fail(f"no expectations for kind {kind}")


def groups(kind, summary):
    """The snapshot groups of a run: (series suffix, grains, bonds or None, lattice nodes or None, grains held
    fixed) for each: one group "" (particles.pvd, ...), or one per case of a sweep ("_caseK")."""
    res = summary["results"]
    if kind == "cylinder_array":
        return [(f"_case{k}", 1, None, (c["case"]["cell"],) * 2, True) for k, c in enumerate(res["cases"])]
    if kind == "porous_flow":
        return [(f"_case{k}", c["discs"], None, tuple(c["size"]), True) for k, c in enumerate(res["cases"])]
    if kind == "pressure_diffusion":
        return [("", res["grains"], None, tuple(res["nodes"]), True)]
    particles, bonds, nodes = expectations(kind, summary)
    return [("", particles, bonds, nodes, False)]


def fluid_radius(kind, summary):
    scene = summary["scene"]
    for section in ("fluid", "consolidation", "terzaghi", "pressure_diffusion"):
        if kind in ("fracture", section) and "fluid_radius" in scene.get(section, {}):
            return scene[section]["fluid_radius"]
    return 1.0


def main(run):
    summary = json.load(open(os.path.join(run, "summary.json")))
    kind = summary["kind"]
    found = groups(kind, summary)
    sweep = found[0][0] != ""
    check(os.path.exists(os.path.join(run, "particles.pvd")) != sweep, f"{run}: particles.pvd of a sweep, or none")
    check(not os.path.exists(os.path.join(run, f"particles_case{len(found)}.pvd")), f"{run}: more groups than cases")
    for suffix, particles, bonds_total, nodes, fixed in found:
        check_group(run, kind, summary, suffix, particles, bonds_total, nodes, fixed)
    print(f"vtk_readback: OK {run} ({kind})")


def check_group(run, kind, summary, suffix, particles, bonds_total, nodes, fixed):
    res = summary["results"]
    fracture = kind == "fracture"
    coupled = nodes is not None

    # Grains.
    snaps = collection(run, "particles" + suffix)
    expected = dict(PARTICLE_ARRAYS, **(PARTICLE_FLUID_ARRAYS if coupled else {}))
    for t, path, obj, units in snaps:
        check(obj.GetNumberOfPoints() == particles, f"{path}: {obj.GetNumberOfPoints()} grains, summary.json says {particles}")
        check(obj.GetNumberOfVerts() == particles, f"{path}: {obj.GetNumberOfVerts()} vertex cells")
        check_arrays(path, obj.GetPointData(), expected, particles, units)
        pd = obj.GetPointData()
        v = arr(pd, "velocity")
        check(np.allclose(arr(pd, "speed"), np.hypot(v[:, 0], v[:, 1]), rtol=1e-12, atol=0), f"{path}: speed is not |velocity|")
        check(np.array_equal(arr(pd, "id"), np.arange(particles)), f"{path}: ids are not 0..n-1")
        if fixed:
            for name, want in [("velocity", 0.0), ("mass", -1.0), ("moment_of_inertia", -1.0), ("contact_count", 0)]:
                check(np.all(arr(pd, name) == want), f"{path}: {name} of grains held fixed is not {want}")
        print(f"vtk_readback: {os.path.basename(path)}: {particles} grains, {len(expected)} arrays, t = {t:g} s")
    if kind == "pressure_diffusion":
        # Snapshot 0 before the drainage, then one at each profile of profiles.csv, at step x dt.
        header, rows = read_csv(os.path.join(run, "profiles.csv"))
        steps = sorted({float(r[header.index("step")]) for r in rows})
        dt = summary["derived"]["units"]["timestep"]
        want = [0.0] + [k * dt for k in steps]
        check([t for t, _, _, _ in snaps] == want, f"snapshot times {[t for t, _, _, _ in snaps]}, profiles.csv {want}")
        print(f"vtk_readback: snapshot times = 0 and the {len(steps)} profile times of profiles.csv")
    t_last, path, grains, _ = snaps[-1]
    check_glyphs(path, grains)
    if fracture:
        header, rows = read_csv(os.path.join(run, "history.csv"))
        last = dict(zip(header, map(float, rows[-1])))
        check(abs(last["time"] - t_last) <= 1e-12 * max(1.0, t_last), f"last history row at {last['time']}, last snapshot at {t_last}")
        pd = grains.GetPointData()
        m, v, w = arr(pd, "mass"), arr(pd, "velocity"), arr(pd, "angular_velocity")
        inertia = np.where(arr(pd, "moment_of_inertia") < 0, 0.0, arr(pd, "moment_of_inertia"))
        ke = 0.5 * np.sum(m * (v[:, 0] ** 2 + v[:, 1] ** 2) + inertia * w ** 2)
        # The same f64 values summed in another order (a few ulps); history.csv prints 11 significant digits.
        check(abs(ke - last["kinetic_energy"]) <= 1e-9 * abs(last["kinetic_energy"]) + 1e-300,
              f"{path}: kinetic energy {ke}, history.csv {last['kinetic_energy']}")
        print(f"vtk_readback: kinetic energy of the last snapshot {ke:.6e} = history.csv {last['kinetic_energy']:.6e}")
    if kind == "coupled_demo":
        header, rows = read_csv(os.path.join(run, "series.csv"))
        last = dict(zip(header, map(float, rows[-1])))
        check(last["step"] == t_last, f"last series row at step {last['step']}, last snapshot at {t_last}")
        pd = grains.GetPointData()
        m, v = arr(pd, "mass"), arr(pd, "velocity")
        w, inertia = arr(pd, "angular_velocity"), arr(pd, "moment_of_inertia")
        ke = 0.5 * np.sum(m * (v[:, 0] ** 2 + v[:, 1] ** 2) + inertia * w ** 2)
        # f64 values summed in another order (a few ulps); series.csv prints 11 significant digits.
        for got, col in [(np.sum(m * v[:, 0]), "grain_momentum_x"), (np.sum(m * v[:, 1]), "grain_momentum_y"),
                         (ke, "grain_kinetic_energy")]:
            check(abs(got - last[col]) <= 1e-9 * abs(last[col]), f"{path}: {col} {got}, series.csv {last[col]}")
        print("vtk_readback: grain momentum and kinetic energy of the last snapshot = series.csv")
    if kind == "terminal_velocity":
        v = arr(grains.GetPointData(), "velocity")
        want = res["disc_velocity_physical"]
        # The writer's lattice-to-physical product against the summary's: a few ulps.
        check(abs(v[0, 0] - want) <= 1e-12 * abs(want), f"{path}: disc velocity {v[0, 0]}, summary.json {want}")
        print(f"vtk_readback: disc velocity {v[0, 0]:.6e} = summary.json")

    # Bonds.
    if bonds_total is None:
        check(not os.path.exists(os.path.join(run, "bonds.pvd")), f"{run}: a bond series without bonds")
        bonds_total = 0
    snaps = collection(run, "bonds" + suffix) if bonds_total else []
    for t, path, obj, units in snaps:
        check(obj.GetNumberOfLines() == bonds_total, f"{path}: {obj.GetNumberOfLines()} bond lines, summary.json says {bonds_total}")
        check(obj.GetNumberOfPoints() == particles, f"{path}: {obj.GetNumberOfPoints()} points")
        check_arrays(path, obj.GetCellData(), BOND_ARRAYS, bonds_total, units)
        cd = obj.GetCellData()
        intact, mode = arr(cd, "intact"), arr(cd, "break_mode")
        check(np.array_equal(intact == 1, mode == 0), f"{path}: break_mode 0 is not exactly the intact bonds")
        pairs = arr(cd, "pair")
        lines = obj.GetLines()
        ids = vtk.vtkIdList()
        lines.InitTraversal()
        k = 0
        while lines.GetNextCell(ids):
            check((ids.GetId(0), ids.GetId(1)) == tuple(pairs[k]), f"{path}: line {k} joins {ids.GetId(0)}, {ids.GetId(1)}; pair says {pairs[k]}")
            k += 1
        print(f"vtk_readback: {os.path.basename(path)}: {bonds_total} bonds ({int(np.sum(intact == 0))} broken), t = {t:g} s")
    if not snaps:
        finish_lattice(run, kind, summary, suffix, nodes, coupled, fracture)
        return
    t, path, obj, _ = snaps[-1]
    cd = obj.GetCellData()
    mode, when = arr(cd, "break_mode"), arr(cd, "break_time")
    recorded = (mode >= 1) & (mode <= 3)
    names = {1: "tension", 2: "shear", 3: "compression"}
    if fracture:
        header, rows = read_csv(os.path.join(run, "breaks.csv"))
        table = sorted((float(r[header.index("time")]), r[header.index("mode")]) for r in rows)
    else:
        header, rows = read_csv(os.path.join(run, "broken_bonds.csv"))
        table = sorted((float(r[header.index("time")]), r[header.index("mode")]) for r in rows)
    ours = sorted((float(x), names[int(mm)]) for x, mm in zip(when[recorded], mode[recorded]))
    check(len(ours) == len(table) == res["broken_bonds"], f"{path}: {len(ours)} recorded breaks, table {len(table)}, summary {res['broken_bonds']}")
    for (ta, ma), (tb, mb) in zip(ours, table):
        # The CSV prints 10 significant digits.
        check(ma == mb and abs(ta - tb) <= 1e-9 * max(abs(tb), 1e-12), f"{path}: break ({ta}, {ma}) vs table ({tb}, {mb})")
    print(f"vtk_readback: {len(ours)} recorded breaks: times and modes equal the break table")
    finish_lattice(run, kind, summary, suffix, nodes, coupled, fracture)


def finish_lattice(run, kind, summary, suffix, nodes, coupled, fracture):
    """The lattice series (coupled runs)."""
    if not coupled:
        check(not os.path.exists(os.path.join(run, "lattice.pvd")), f"{run}: a lattice series without a fluid")
    else:
        snaps = collection(run, "lattice" + suffix)
        nx, ny = nodes
        for t, path, obj, units in snaps:
            dims = obj.GetDimensions()
            check(tuple(dims) == (nx, ny, 1), f"{path}: dimensions {dims}, summary.json nodes {nx} x {ny}")
            check_arrays(path, obj.GetPointData(), LATTICE_ARRAYS, nx * ny, units)
            eps = arr(obj.GetPointData(), "solid_fraction")
            check(np.all((eps >= 0) & (eps <= 1)), f"{path}: solid fraction outside [0, 1]")
            kinds = arr(obj.GetPointData(), "node_kind")
            check(set(np.unique(kinds)) <= {0, 1, 2, 3}, f"{path}: node kinds {np.unique(kinds)}")
            check(np.array_equal(kinds == 1, (eps > 0) & (kinds != 3) & (kinds != 2)), f"{path}: node_kind 1 is not the covered nodes")
            # The grains are on the lattice in every snapshot, the first (t = 0, mapped before it) too.
            check(np.any(eps > 0), f"{path}: no grain on the lattice")
            print(f"vtk_readback: {os.path.basename(path)}: {nx} x {ny} nodes, t = {t:g} s")
        # t = 0: the grains as the fluid sees them cover their area (eq. 4.4's exact cell areas; the grains lie
        # inside the lattice): sum of eps h^2 = sum of pi a b f^2, f the fluid radius.
        t0, path, obj, _ = snaps[0]
        h = obj.GetSpacing()[0]
        grains = collection(run, "particles" + suffix)[0][2]
        axes = arr(grains.GetPointData(), "semi_axes")
        f = fluid_radius(kind, summary)
        area = float(np.sum(np.pi * axes[:, 0] * axes[:, 1])) * f * f
        covered = float(np.sum(arr(obj.GetPointData(), "solid_fraction").astype(float))) * h * h
        # eps stored as float32: 2^-24 relative each, summed.
        check(t0 == 0.0 and abs(covered - area) <= 1e-6 * area, f"{path}: covered area {covered}, the grains' {area}")
        print(f"vtk_readback: the t = 0 lattice covers the grains' area {area:.6e}")
        if kind in ("porous_flow", "pressure_diffusion"):
            pd = obj.GetPointData()
            p = arr(pd, "pressure").astype(float).reshape(ny, nx)
            kinds = arr(pd, "node_kind").reshape(ny, nx)
            scene = summary["scene"]
            if kind == "porous_flow":
                # Case k runs pressure drop k mod m: the west Zou-He side holds it, the east one 0 (the reference).
                drops = scene["porous"]["pressure_drops"]
                dp = drops[int(suffix[len("_case"):]) % len(drops)]
                west, east = p[:, 0], p[:, -1]
            else:
                # Before the drainage: the initial overpressure at the free fluid nodes inside, 0 on the drained
                # Zou-He faces. The columns next to the faces are left out: the file's density is the one the next
                # collision sees, after streaming, so 1/6 of theirs comes from the face (docs/outputs.md).
                dp = scene["pressure_diffusion"]["overpressure"]
                inner = kinds[:, 2:-2] == 0
                west, east = p[:, 2:-2][inner], np.concatenate([p[:, 0], p[:, -1]])
                check(np.all(kinds[:, 0] == 3) and np.all(kinds[:, -1] == 3), f"{path}: the faces are not Zou-He nodes")
            # float32 pressures: 2^-24 relative; the drained side's 0 up to the roundoff of rho - 1 (1e-12 of dp).
            check(np.all(np.abs(west - dp) <= 1e-6 * dp) and np.all(np.abs(east) <= 1e-6 * dp),
                  f"{path}: pressures {west.min()}..{west.max()} and {east.min()}..{east.max()}, expected {dp} and 0")
            print(f"vtk_readback: the lattice's pressure holds {dp} and 0 where the scene imposes them")
    if coupled and fracture:
        t, path, obj, _ = snaps[-1]
        pd = obj.GetPointData()
        p = arr(pd, "pressure").astype(float).reshape(ny, nx)
        u = arr(pd, "velocity").astype(float).reshape(ny, nx, 3)
        eps = arr(pd, "solid_fraction").astype(float).reshape(ny, nx)
        speed = np.hypot(u[..., 0], u[..., 1])
        header, rows = read_csv(os.path.join(run, "history.csv"))
        last = dict(zip(header, map(float, rows[-1])))
        vmax = float(np.max(speed[eps < 1.0]))
        # The file stores float32: 2^-24 relative rounding of each velocity component (and of ε near 1).
        check(abs(vmax - last["max_fluid_speed"]) <= 1e-6 * last["max_fluid_speed"] + 1e-30,
              f"{path}: max fluid speed {vmax}, history.csv {last['max_fluid_speed']}")
        # Centre line: the fluid-fraction-weighted mean over rows within one largest grain radius of the centre row
        # (as the run computes it for centerline_pressure.csv).
        scene = open(os.path.join(run, "scene.toml")).read()
        radius_max = float(re.search(r"(?m)^\s*radius_max\s*=\s*([-+0-9.eE]+)", scene).group(1))
        spacing = float(re.search(r"(?m)^\s*spacing\s*=\s*([-+0-9.eE]+)", scene).group(1))
        # Rust's f64::round (halves away from zero) of this positive ratio.
        half = max(1, int(math.floor(radius_max / spacing + 0.5)))
        row = ny // 2
        ya, yb = max(0, row - half), min(ny - 1, row + half)
        wgt = 1.0 - eps[ya:yb + 1, :]
        with np.errstate(invalid="ignore", divide="ignore"):
            line = np.sum(wgt * p[ya:yb + 1, :], axis=0) / np.sum(wgt, axis=0)
        header, rows = read_csv(os.path.join(run, "centerline_pressure.csv"))
        table = np.array([float(x) for x in rows[-1][1:]])
        check(len(table) == nx, f"centerline_pressure.csv has {len(table)} columns of x, the lattice {nx}")
        ok = np.isfinite(table)
        scale = float(np.max(np.abs(p)))
        # float32 pressure and ε in the file: each term off by ~6e-8 of the largest pressure.
        err = float(np.max(np.abs(line[ok] - table[ok])))
        check(err <= 1e-6 * scale, f"{path}: centre-line pressure differs from centerline_pressure.csv by {err} (scale {scale})")
        print(f"vtk_readback: centre-line pressure and max fluid speed of the last lattice snapshot match the tables (max diff {err:.2e})")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        fail("usage: vtk_readback.py RUN_DIR")
    main(sys.argv[1])
