"""The eigen-solve of a casting-like tet4 mesh (issue 37): a two-cylinder block section in mm
(300 x 180 x 250, bores D 131 at 150 pitch, water-jacket annuli open at the deck, head-bolt
holes, an oil gallery and a crank-side pocket), free-free, made by Gmsh with linear
tetrahedra; the default size 2.7 mm gives about 754k DOF, the size of the CT-scan casting of the
issue (748k DOF).

`linercav modes` runs twice: at the default shift (100 Hz, below the lowest modes) and at
--shift-hz 20000 (far from them: the shift is moved, one factorisation more). Prints the whole
process's wall time and peak RSS, the phases, the certificate, and the ratio of the two runs.
With --scipy, SciPy's eigsh (SuperLU shift-invert) on the same matrices in a child process
under an address-space cap and a time limit (it ran out of memory on the issue's casting).

Run through benches/casting.sh, which makes a private venv with gmsh and scipy.
"""
import argparse, json, os, resource, subprocess, sys, time, math

import gmsh

ap = argparse.ArgumentParser()
ap.add_argument("--size-mm", type=float, default=2.7, help="Gmsh element size")
ap.add_argument("--count", type=int, default=20)
ap.add_argument("--out", default="bench-out")
ap.add_argument("--bin", default="target/release/linercav")
ap.add_argument("--scipy", action="store_true", help="also SciPy eigsh on the same matrices")
ap.add_argument("--scipy-gb", type=float, default=20.0, help="address-space cap of SciPy's run")
ap.add_argument("--scipy-s", type=float, default=900.0, help="time limit of SciPy's run")
a = ap.parse_args()
os.makedirs(a.out, exist_ok=True)
msh = os.path.join(a.out, f"casting_tet4_{a.size_mm:g}mm.msh")


def make_mesh(path, h):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    occ = gmsh.model.occ
    blk = occ.addBox(0, 0, 0, 300, 180, 250)
    cuts = []
    for x in (75, 225):
        cuts.append((3, occ.addCylinder(x, 90, -1, 0, 0, 252, 65.5)))
        outer = occ.addCylinder(x, 90, 80, 0, 0, 171, 80)
        inner = occ.addCylinder(x, 90, 79, 0, 0, 173, 72)
        jacket, _ = occ.cut([(3, outer)], [(3, inner)])
        cuts += jacket
        for dx, dy in ((-62, -62), (62, -62), (-62, 62), (62, 62)):
            cuts.append((3, occ.addCylinder(x + dx, 90 + dy, 40, 0, 0, 211, 7)))
    cuts.append((3, occ.addCylinder(-1, 20, 30, 302, 0, 0, 8)))
    cuts.append((3, occ.addBox(20, 30, -1, 260, 120, 35)))
    occ.cut([(3, blk)], cuts)
    occ.synchronize()
    gmsh.model.addPhysicalGroup(3, [v[1] for v in gmsh.model.getEntities(3)], 1, "casting")
    gmsh.option.setNumber("Mesh.MeshSizeMin", h)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.option.setNumber("Mesh.Algorithm3D", 10)
    gmsh.option.setNumber("General.NumThreads", 2)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.model.mesh.generate(3)
    gmsh.write(path)
    gmsh.finalize()


if not os.path.exists(msh):
    make_mesh(msh, a.size_mm)

# grey cast iron; the deck is in mm (--unit mm), the constants SI
mat = ["--unit", "mm", "--youngs", "1.2e11", "--poisson", "0.26", "--density", "7200"]


def modes(extra):
    cmd = ["/usr/bin/time", "-f", "RSS_KB %M", a.bin, "modes", "--mesh", msh, *mat,
           "--count", str(a.count), "--json", *extra]
    t0 = time.perf_counter()
    run = subprocess.run(cmd, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - t0
    kb = [l for l in run.stderr.splitlines() if l.startswith("RSS_KB")][-1].split()[1]
    return wall, int(kb) * 1024 / 1e9, json.loads(run.stdout)


rows = [("default shift", []), ("--shift-hz 20000", ["--shift-hz", "20000"])]
results = [(label, *modes(extra)) for label, extra in rows]
base = results[0][1]
print(f"casting-like tet4 section: {results[0][3]['dofs']} DOF, {a.count} modes, free-free ({msh})")
print("peak: resident memory (VmHWM) in GB of 1e9 bytes, the unit of issue 37's floors, and in GiB")
print(f"{'run':<18} {'wall s':>8} {'ratio':>6} {'peak GB':>8} {'GiB':>6} {'shift Hz':>9} {'Sturm':>6}  phases [s]")
for label, wall, gb, out in results:
    ph = " ".join(f"{k} {v:.1f}" for k, v in out["timings"].items())
    print(f"{label:<18} {wall:8.1f} {wall / base:6.2f} {gb:8.2f} {gb * 1e9 / 2**30:6.2f} "
          f"{out['shift_hz']:9.1f} {str(out['sturm_count_ok']):>6}  {ph}")
f = results[0][3]["frequencies_hz"]
print("frequencies [Hz]:", " ".join(f"{x:.1f}" for x in f))
same = max(abs(x - y) / y for x, y in zip(results[1][3]["frequencies_hz"], f) if y > 1.0)
print(f"the two runs' elastic frequencies agree within {same:.1e} (relative)")

if a.scipy:
    mtx = os.path.join(a.out, "casting_mtx")
    subprocess.run([a.bin, "export-matrices", "--mesh", msh, *mat, "--out", mtx], check=True,
                   capture_output=True)
    sigma = -(2 * math.pi * results[0][3]["shift_hz"]) ** 2
    code = f"""
import resource, time, scipy.io, scipy.sparse.linalg as sla
cap = int({a.scipy_gb} * 1e9)
resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
K = scipy.io.mmread("{mtx}/K.mtx").tocsc(); M = scipy.io.mmread("{mtx}/M.mtx").tocsc()
t0 = time.perf_counter()
sla.eigsh(K, k={a.count}, M=M, sigma={sigma!r}, which="LM", return_eigenvectors=False)
print("SCIPY_S", time.perf_counter() - t0,
      resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e9)
"""
    try:
        r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           timeout=a.scipy_s, env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
        line = [l for l in r.stdout.splitlines() if l.startswith("SCIPY_S")]
        if line:
            s, gb = map(float, line[0].split()[1:])
            print(f"SciPy eigsh (solve only): {s:.1f} s, peak {gb:.2f} GB; "
                  f"linercav whole process / SciPy solve: {base / s:.3f}")
        else:
            print(f"SciPy eigsh failed under a {a.scipy_gb:g} GB cap: "
                  f"{(r.stderr.strip().splitlines() or ['?'])[-1]}")
    except subprocess.TimeoutExpired:
        print(f"SciPy eigsh did not finish within {a.scipy_s:g} s")
