#!/usr/bin/python3
"""The tables of docs/validation.md that take more than a test's time, measured where the script runs.

Each group runs the commands its section of validation.md lists and prints the section's table in markdown, headed by
the CPU model, instruction set, thread count and date; a run whose summary.json is already in the output folder is read
back instead (--reuse), so a group can be resumed or re-tabulated:

    benchmarks/validation_tables.py --out runs/validation compression      # about 15 minutes on 2 cores
    benchmarks/validation_tables.py --out runs/validation needle_volumetric # about 6 minutes
    benchmarks/validation_tables.py --out runs/validation layers           # about 8 minutes
    benchmarks/validation_tables.py --out runs/validation brain            # about 12 minutes
    benchmarks/validation_tables.py --out runs/validation needle_models stress_miss

Groups: compression (uniform clouds with and without nodal_average; the graded clouds and uniform ones against the
CalculiX reference), needle_volumetric (the small sample's three grids, per point and nodal_average), layers and brain
(the paper's Ogden materials against a uniform neo-Hookean law, compared by `mtled compare`), needle_models (the
kinematic needle against the rigid frictional-contact one, docs/needle-models.md) and stress_miss (the written stress
integrated over the deformed body against the platen force). The last two read result.vtu with VTK (Debian
python3-paraview) and numpy.
"""
import argparse
import csv
import datetime
import json
import platform
import subprocess
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "share/scenes"
NEO_HOOKEAN = '/materials=[{"type":"neo_hookean","mu":1000,"D":4.02684e-5,"density":1000}]'
UNIFORM = ["/mesh/mesh_size=null", "/mesh/refine_rims=false"]
# The CalculiX reference at 5, 10, 15 and 20% compression (N): validation.md, extrapolated from the axisymmetric meshes.
CALCULIX = (0.1180, 0.2573, 0.4195, 0.6043)


def cpu_line(threads):
    fields = {}
    for line in Path("/proc/cpuinfo").read_text().splitlines():
        key, _, value = line.partition(":")
        fields.setdefault(key.strip(), value.strip())
        if key.strip() == "flags":
            break
    flags = " " + fields.get("flags", "")
    isa = "AVX-512" if " avx512f" in flags else "AVX2" if " avx2" in flags else platform.machine()
    return (f"{fields.get('model name', 'unknown CPU')}, family {fields.get('cpu family', '?')} model "
            f"{fields.get('model', '?')} ({isa}), {threads} threads, {datetime.date.today().isoformat()}")


class Runner:
    def __init__(self, mtled, out, threads, reuse):
        self.mtled, self.out, self.threads, self.reuse = mtled, out, threads, reuse

    def run(self, name, scene, overrides=()):
        """Runs `scene` with the --set overrides into out/name; returns its summary.json and folder."""
        folder = self.out / name
        summary_file = folder / "summary.json"
        if not (self.reuse and summary_file.exists()):
            args = [self.mtled, "run", str(SCENES / scene), "-o", str(folder), "--threads", str(self.threads),
                    "--no-progress"]
            for o in overrides:
                args += ["--set", o]
            start = time.monotonic()
            with open(str(folder) + ".log", "w") as log:
                code = subprocess.run(args, stdout=log, stderr=subprocess.STDOUT).returncode
            print(f"  {name}: exit {code}, {time.monotonic() - start:.0f} s", flush=True)
            if code != 0:
                raise SystemExit(f"{folder}: mtled exited with {code} (see {folder}.log)")
        return json.loads(summary_file.read_text()), folder

    def compare(self, test, reference):
        args = [self.mtled, "compare", str(self.out / test), str(self.out / reference), "--json"]
        return json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)


# Both platens' contact off (the shipped scene has it on): the CalculiX reference's problem.
NO_PLATENS = ['/boundaries/0/platen="none"', '/boundaries/1/platen="none"']


def relaxed_forces(folder, boundary="top"):
    """The platen's |f_z| at each relaxed increment (reactions.csv holds relaxed states only): the boundary's face
    and, with its `platen` option, the surface that rolled onto the platen (the set "<boundary>_contact")."""
    totals = {}
    with open(folder / "reactions.csv") as f:
        for row in csv.DictReader(f):
            if row["set"] in (boundary, boundary + "_contact"):
                totals[row["time_s"]] = totals.get(row["time_s"], 0.0) + float(row["fz_N"])
    return [abs(force) for force in totals.values()]


def platen_force(summary, boundary="top"):
    """The platen's f_z in the final state: the boundary's face plus what rolled onto the platen."""
    reactions = summary["final_reactions_N"]
    return reactions[boundary][2] + reactions.get(boundary + "_contact", [0.0, 0.0, 0.0])[2]


def sized(summary):
    return f"{summary['nodes']:,} / {summary['integration_points']:,}"


def change(new, old):
    return f"{100 * (new / old - 1):+.1f}%"


def compression(runner):
    print("### Uniform clouds: top force at 20%\n")
    print("| target_nodes | nodes / integration points | force, per-point J (the paper's) | change | "
          "force, `nodal_average` | change |\n| --- | --- | --- | --- | --- | --- |")
    previous = {}
    for target in (2000, 5000, 12000, 25000):
        cells = []
        for treatment, extra in (("per_point", ["/volumetric=null"]), ("nodal_average", [])):
            if treatment == "per_point" and target == 25000:
                cells += ["not run", ""]
                continue
            summary, folder = runner.run(f"compression-uniform-{target}-{treatment}", "compression_semiconfined.json",
                                         UNIFORM + [f"/mesh/target_nodes={target}"] + extra)
            force = relaxed_forces(folder)[-1]
            cells += [f"{force:.4f} N", change(force, previous[treatment]) if treatment in previous else ""]
            previous[treatment] = force
        print(f"| {target} | {sized(summary)} | " + " | ".join(cells) + " |")

    softer = []  # per point with D ten times larger (nu about 0.41): less locking
    for target in (2000, 5000):
        _, folder = runner.run(f"compression-uniform-{target}-per_point-D10", "compression_semiconfined.json",
                               UNIFORM + [f"/mesh/target_nodes={target}", "/volumetric=null", "/materials/0/D=5.57738e-4"])
        softer.append(relaxed_forces(folder)[-1])
    print(f"\nper point, D ten times larger: {softer[0]:.4f} N and {softer[1]:.4f} N ({change(softer[1], softer[0])})")
    print("\n### Against the CalculiX reference: top force at 5, 10, 15 and 20%\n")
    print("| mtled | nodes | 5% | 10% | 15% | 20% |\n| --- | --- | --- | --- | --- | --- |")
    # The reference has no contact: its side passes through the platens from about 15% (stability.md), so mtled
    # solves the same problem with the platens' contact off; the shipped platens follow.
    graded = [("**shipped scene**: rims refined, h = 2 mm (0.5 mm at the rims)", "compression-graded-2mm", []),
              ("rims refined, h = 1.41 mm (0.35 mm)", "compression-graded-1.41mm", ["/mesh/mesh_size=0.00141"]),
              ("rims refined, h = 1 mm (0.25 mm)", "compression-graded-1mm", ["/mesh/mesh_size=0.001"])]
    uniform = [("uniform, target_nodes 4,000 (`$uniform` above)", "compression-uniform-4000-nodal_average",
                UNIFORM + ["/mesh/target_nodes=4000"]),
               ("uniform, target_nodes 25,000", "compression-uniform-25000-nodal_average",
                UNIFORM + ["/mesh/target_nodes=25000"])]
    without = {}
    for label, name, overrides in graded + uniform:
        contact_off = [] if name.startswith("compression-uniform") else NO_PLATENS
        summary, folder = runner.run(name + ("-no-platens" if contact_off else ""), "compression_semiconfined.json",
                                     overrides + contact_off)
        forces = relaxed_forces(folder)
        without[name] = forces[-1]
        cells = [f"{f:.4f} ({change(f, ref)})" for f, ref in zip(forces, CALCULIX)]
        print(f"| {label} | {summary['nodes']:,} | " + " | ".join(cells) + f" |  <!-- {summary['steps']} steps, "
              f"solve {summary['solve_time_s']:.0f} s, stable step {summary['stable_time_step_s']:.3g} s -->")
    print("\n### With the platens (`platen`: frictionless on both faces, as shipped): top platen's force at 20%\n")
    print("| mtled | force at 20% | against the same cloud without | against the reference (no contact) |\n"
          "| --- | --- | --- | --- |")
    for label, name, overrides in graded:
        summary, folder = runner.run(name, "compression_semiconfined.json", overrides)
        force = relaxed_forces(folder)[-1]
        print(f"| {label} | {force:.4f} N | {change(force, without[name])} | {change(force, CALCULIX[-1])} |  "
              f"<!-- {summary['steps']} steps, solve {summary['solve_time_s']:.0f} s -->")


def needle_volumetric(runner):
    print("### The small sample's grids, 2,000 load steps, tolerance 1e-5: needle force at 15 mm\n")
    targets = (7480, 17730, 30294)
    settings = ["/integrator/load_steps=2000", "/integrator/tolerance=1e-5"]
    header = None
    for label, treatment, extra in (("per point (default)", "per_point", []),
                                    ("`nodal_average`", "nodal_average", ["/volumetric/type=nodal_average"])):
        forces, nodes, solves = [], [], []
        for target in targets:
            summary, _ = runner.run(f"needle-{target}-{treatment}", "needle_small_sample.json",
                                    settings + [f"/mesh/target_nodes={target}"] + extra)
            forces.append(summary["needle"]["final_force_N"])
            nodes.append(summary["nodes"])
            solves.append(summary["solve_time_s"])
        if header is None:
            header = (f"| volumetric treatment | {nodes[0]:,} nodes | {nodes[1]:,} | {nodes[2]:,} | "
                      "change, coarse to moderate | moderate to refined |")
            print(header + "\n| --- | --- | --- | --- | --- | --- |")
        print(f"| {label} | " + " | ".join(f"{f:.4f} N" for f in forces) +
              f" | {change(forces[1], forces[0])} | {change(forces[2], forces[1])} |  <!-- solve " +
              " / ".join(f"{s:.1f}" for s in solves) + " s -->")


def describe_pair(name, ogden, neo):
    print(f"  {name}: {ogden['nodes']:,} nodes, {ogden['integration_points']:,} integration points; Ogden "
          f"{ogden['steps']} steps, solve {ogden['solve_time_s']:.0f} s, force "
          f"{ogden['needle']['final_force_N']:.4g} N, error bound {ogden['integrator'].get('error_bound_m', float('nan')):.3g} m,"
          f" status {ogden['status']}; neo-Hookean {neo['steps']} steps, force {neo['needle']['final_force_N']:.4g} N, "
          f"status {neo['status']}")


def field_row(label, comparison):
    nrmse = [comparison["nrmse"][c] for c in ("ux", "uy", "uz")]
    rms = [comparison["rmse_m"][c] for c in ("ux", "uy", "uz")]
    largest = [comparison["max_abs_difference_m"][c] for c in ("ux", "uy", "uz")]
    return (f"| {label} | " + " | ".join(f"{v:.2e}" for v in nrmse) + " | " +
            " / ".join(f"{1e3 * v:.2g}" for v in rms) + " mm | " + " / ".join(f"{1e3 * v:.2g}" for v in largest) +
            " mm |")


def layers(runner):
    cases = [("shaft's surface (default), 15 mm", "layers-15mm", []),
             ("nodes near the axis (the paper's reading), 15 mm", "layers-15mm-nodes",
              ["/needle/driven=nodes_near_axis", "/needle/drive=since_capture", "/needle/lateral=held"]),
             ("shaft's surface (default), 5 mm", "layers-5mm", ["/needle/depth=0.005"])]
    rows = []
    for label, name, overrides in cases:
        ogden, _ = runner.run(f"{name}-ogden", "needle_large_sample_layers.json", overrides)
        neo, _ = runner.run(f"{name}-neo", "needle_large_sample_layers.json", overrides + [NEO_HOOKEAN])
        describe_pair(name, ogden, neo)
        force = f"{ogden['needle']['final_force_N']:.3g} / {neo['needle']['final_force_N']:.3g} N"
        rows.append(field_row(f"{label} | {ogden['needle'].get('driven_nodes', '')} | {force}",
                              runner.compare(f"{name}-neo", f"{name}-ogden")))
    print("\n| needle, depth | driven | needle force Ogden / neo-Hookean | NRMSE u_x | u_y | u_z | RMS difference "
          "| largest node difference |\n| --- | --- | --- | --- | --- | --- | --- | --- |")
    print("\n".join(rows))


def brain(runner):
    rows = []
    # Under the unlimited drag the neo-Hookean run folds beside the entry at 100 mm: the fold check warns, so that both
    # runs end and the fields can be compared (the folds are in summary.json's monitors record).
    unlimited = ["/needle/drag_limit=null", "/monitors/inversion=warn"]
    for label, name, overrides in (("mtled, the paper's unlimited drag", "brain-unlimited", unlimited),
                                   ("mtled, the drag limited to 6 mm (the shipped scene)", "brain-limited", [])):
        ogden, _ = runner.run(f"{name}-ogden", "needle_brain_phantom.json", overrides)
        neo, _ = runner.run(f"{name}-neo", "needle_brain_phantom.json", overrides + [NEO_HOOKEAN])
        describe_pair(name, ogden, neo)
        rows.append(field_row(label, runner.compare(f"{name}-neo", f"{name}-ogden")))
    where_fields_differ(runner.out / "brain-unlimited-ogden", runner.out / "brain-unlimited-neo", [0.025, 0.006, 0.07])
    print("\n| 100 mm | NRMSE u_x | u_y | u_z | RMS difference | largest node difference |\n"
          "| --- | --- | --- | --- | --- | --- |")
    print("\n".join(rows))


def read_result(folder):
    """(reference points, displacement, cells as point-index arrays, cell arrays by name), lengths in metres."""
    import numpy as np  # Debian python3-numpy and python3-paraview (its vtk module), as scripts/render_result.py
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(folder / "result.vtu"))
    reader.Update()
    grid = reader.GetOutput()
    unit = grid.GetFieldData().GetAbstractArray("LENGTH_UNIT")
    scale = 1e-3 if unit is not None and unit.GetValue(0) == "mm" else 1.0
    points = scale * vtk_to_numpy(grid.GetPoints().GetData())
    displacement = scale * vtk_to_numpy(grid.GetPointData().GetArray("displacement"))
    cells = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 4)
    arrays = {grid.GetCellData().GetArrayName(i): vtk_to_numpy(grid.GetCellData().GetArray(i))
              for i in range(grid.GetCellData().GetNumberOfArrays())}
    return np, points, displacement, cells, arrays


def surface_deflection(folder, depth, radius=0.0025):
    """U2/U1: the largest downward displacement of the top face's nodes within `radius` of the axis (x = y = 0)
    over the needle's depth (the paper's Fig. 3)."""
    np, points, u, _, _ = read_result(folder)
    top = points[:, 2] > points[:, 2].max() - 1e-9
    near = top & (np.hypot(points[:, 0], points[:, 1]) < radius)
    return float(-u[near, 2].min()) / depth


def transient_forces(folder, depths_mm):
    """The relaxation's transient: the first row of needle_transient.csv at or past each depth."""
    with open(folder / "needle_transient.csv") as f:
        rows = [(float(r["depth_m"]), float(r["transient_force_N"])) for r in csv.DictReader(f)]
    return [next(force for depth, force in rows if depth >= 1e-3 * d - 1e-12) for d in depths_mm]


PAPER_NEEDLE = ["/needle/driven=nodes_near_axis", "/needle/drive=since_capture", "/needle/lateral=held"]


def needle_models(runner):
    kinematic, k_folder = runner.run("kinematic-paper", "needle_small_sample.json", PAPER_NEEDLE + [
        "/integrator/load_steps=2000", "/integrator/tolerance=1e-5", "/integrator/time_step_factor=0.9"])
    contact, c_folder = runner.run("contact", "needle_small_sample_contact.json")
    comparison = runner.compare("contact", "kinematic-paper")
    print("| | `kinematic` (C_D = 0.4) | `rigid_contact` (mu = 0.3) |\n| --- | --- | --- |")
    pair = (kinematic, contact)
    rows = [("nodes / integration points", [sized(r) for r in pair]),
            ("steps (2000 load steps + convergence)", [f"{r['steps']:,}" for r in pair]),
            ("wall time (setup + solve)", [f"{r['setup_time_s'] + r['solve_time_s']:.0f} s" for r in pair]),
            ("driven / contact nodes at the end", [str(r["needle"]["driven_nodes"]) for r in pair]),
            ("puncture depth", [f"{1e3 * r['needle']['puncture_depth_m']:.4g} mm" for r in pair]),
            ("needle force at 15 mm, during the insertion",
             [f"{transient_forces(f, [15.0])[0]:.3f} N" for f in (k_folder, c_folder)]),
            ("final needle force (after convergence)", [f"{r['needle']['final_force_N']:.3f} N" for r in pair]),
            ("max displacement", [f"{1e3 * r['max_displacement_m']:.2f} mm" for r in pair]),
            ("surface deflection beside the needle, U2/U1",
             [f"{surface_deflection(f, 0.015):.3f}" for f in (k_folder, c_folder)])]
    for label, cells in rows:
        print(f"| {label} | " + " | ".join(cells) + " |")
    nrmse = " / ".join(f"{comparison['nrmse'][c]:.3g}" for c in ("ux", "uy", "uz"))
    print(f"\ncontact against kinematic: NRMSE {nrmse}; solve per step "
          f"{1e3 * kinematic['solve_time_s'] / kinematic['steps']:.1f} / "
          f"{1e3 * contact['solve_time_s'] / contact['steps']:.1f} ms; constraint factorisations "
          f"{kinematic['constraint_factorisations']} / {contact['constraint_factorisations']}")

    default, d_folder = runner.run("kinematic-default", "needle_small_sample.json")
    depths = [1.5 * k for k in range(1, 11)]
    print("\n| depth (mm) | " + " | ".join(f"{d:g}" for d in depths) + " |\n" + "| --- " * 11 + "|")
    for label, folder in (("`kinematic` (N), default", d_folder), ("`kinematic` (N), the paper's reading", k_folder),
                          ("`rigid_contact` (N)", c_folder)):
        print(f"| {label} | " + " | ".join(f"{f:.4f}" for f in transient_forces(folder, depths)) + " |")


def stress_miss(runner):
    """The integral of the written sigma_zz over the deformed body against the current height times the top force."""
    height, push = 0.017, 0.0017
    cases = [(f"{h:g} mm", f"stress-uniform-{h:g}mm", ["/mesh/refine_rims=false", f"/mesh/mesh_size={h * 1e-3:g}"])
             for h in (3, 2, 1.5, 1)]
    cases.append(("graded to the rims (2 mm, 0.5 mm at the rims)", "stress-graded", []))
    cells, labels = [], []
    for label, name, overrides in cases:
        summary, folder = runner.run(name, "compression_semiconfined.json", overrides + [
            f"/boundaries/1/displacement=[0,0,{-push:g}]", "/integrator/relaxed_increments=1"])
        np, points, u, tets, arrays = read_result(folder)
        x = points + u
        a, b, c, d = (x[tets[:, k]] for k in range(4))
        volume = np.abs(np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a)) / 6.0
        integral = float(np.sum(arrays["cauchy_stress"][:, 8] * volume))
        expected = (height - push) * platen_force(summary)
        labels.append(label)
        cells.append(f"{100 * abs(integral / expected - 1):.2g}%")
    print("| spacing H | " + " | ".join(labels) + " |\n" + "| --- " * (len(labels) + 1) + "|")
    print("| stress of F_bar (written) | " + " | ".join(cells) + " |")


def where_fields_differ(ogden, neo, entry):
    """Node by node, the neo-Hookean field against the Ogden one around a needle entering at `entry` along -z."""
    np, points, u_ogden, _, _ = read_result(ogden)
    _, _, u_neo, _, _ = read_result(neo)
    difference = np.linalg.norm(u_neo - u_ogden, axis=1)
    radial = np.hypot(points[:, 0] - entry[0], points[:, 1] - entry[1])
    far = difference > 5e-3
    print(f"  node by node: {100 * np.mean(difference < 1e-3):.0f}% under 1 mm, {100 * np.mean(difference < 2e-3):.0f}% "
          f"under 2 mm; {far.sum()} nodes over 5 mm, {1e3 * (entry[2] - points[far, 2]).max():.1f} mm under the entry at "
          f"most, {1e3 * radial[far].min():.1f} to {1e3 * radial[far].max():.1f} mm from the axis")
    ring = np.where((radial > 4e-3) & (radial < 5e-3))[0]
    surface = ring[np.argmax(points[ring, 2])]
    print(f"  the surface {1e3 * radial[surface]:.1f} mm from the axis moves down {-1e3 * u_neo[surface, 2]:.1f} mm "
          f"(neo-Hookean) against {-1e3 * u_ogden[surface, 2]:.1f} mm (Ogden); RMS difference within 1 and 2 mm of the "
          "axis " + " and ".join(f"{1e3 * np.sqrt(np.mean(difference[radial < r] ** 2)):.2f}" for r in (1e-3, 2e-3)) + " mm")


GROUPS = {"compression": compression, "needle_volumetric": needle_volumetric, "layers": layers, "brain": brain,
          "needle_models": needle_models, "stress_miss": stress_miss}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("groups", nargs="+", choices=sorted(GROUPS))
    parser.add_argument("--mtled", default=str(ROOT / "build/bin/mtled"))
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--reuse", action="store_true", help="read back runs whose summary.json exists")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    runner = Runner(args.mtled, args.out, args.threads, args.reuse)
    print(f"Measured on {cpu_line(args.threads)}\n")
    for group in args.groups:
        GROUPS[group](runner)
        print()


if __name__ == "__main__":
    main()
