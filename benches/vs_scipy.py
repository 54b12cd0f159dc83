"""Side-by-side: `linercav modes` (whole process) against SciPy eigsh's solve alone, on the same
matrices of a Gmsh-made 10-node-tetrahedron liner-like tube (OD 135, ID 115, L 260 mm), or of a
scene's part (--scene models/engine.toml --part liner: the default liner, 48.7k DOF).

Run through benches/vs_scipy.sh, which makes a private venv with scipy and gmsh.
Each side runs --repeat times (default 3, one after the other); the ratio is of the medians.
Prints the time ratio (machine-independent figure first), every run's time, the largest
relative frequency difference, and the peak memory of both.
"""
import argparse, json, math, os, resource, subprocess, sys, time

import gmsh
import numpy as np
import scipy
import scipy.io
import scipy.sparse.linalg as sla

ap = argparse.ArgumentParser()
ap.add_argument("--size-mm", type=float, default=5.0, help="Gmsh target element size")
ap.add_argument("--count", type=int, default=24)
ap.add_argument("--out", default="bench-out")
ap.add_argument("--bin", default="target/release/linercav")
ap.add_argument("--scene", help="a part of this scene instead of the tube (e.g. models/engine.toml)")
ap.add_argument("--part", default="liner", help="the part of --scene")
ap.add_argument("--repeat", type=int, default=3, help="runs of each side; the ratio is of the medians")
a = ap.parse_args()
if a.repeat < 1:
    sys.exit("--repeat must be at least 1")
os.makedirs(a.out, exist_ok=True)
msh = os.path.join(a.out, f"tube_tet10_{a.size_mm:g}mm.msh")

if not a.scene and not os.path.exists(msh):
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    outer = gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, 0.26, 0.0675)
    inner = gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, 0.26, 0.0575)
    gmsh.model.occ.cut([(3, outer)], [(3, inner)])
    gmsh.model.occ.synchronize()
    gmsh.model.addPhysicalGroup(3, [e[1] for e in gmsh.model.getEntities(3)], name="solid")
    gmsh.option.setNumber("Mesh.MeshSizeMax", a.size_mm * 1e-3)
    gmsh.option.setNumber("Mesh.ElementOrder", 2)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.model.mesh.generate(3)
    gmsh.write(msh)
    gmsh.finalize()

mat = ["--youngs", "140e9", "--poisson", "0.26", "--density", "7200"]
# the model: the tube's mesh with its material, or a part of a scene
model = [a.scene, "--part", a.part] if a.scene else ["--mesh", msh, *mat]
times_ours = []
for _ in range(a.repeat):
    t0 = time.perf_counter()
    run = subprocess.run([a.bin, "modes", *model, "--count", str(a.count), "--json"],
                         capture_output=True, text=True, check=True)
    times_ours.append(time.perf_counter() - t0)
t_ours = float(np.median(times_ours))
ours = json.loads(run.stdout)
rss_ours = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1e6  # GB (ru_maxrss in kB)

mtx = os.path.join(a.out, "mtx")
subprocess.run([a.bin, "export-matrices", *model, "--out", mtx], check=True,
               capture_output=True)
K = scipy.io.mmread(os.path.join(mtx, "K.mtx")).tocsc()
M = scipy.io.mmread(os.path.join(mtx, "M.mtx")).tocsc()
sigma = -(2 * math.pi * ours["shift_hz"]) ** 2
times_scipy = []
for _ in range(a.repeat):
    t0 = time.perf_counter()
    vals = sla.eigsh(K, k=a.count, M=M, sigma=sigma, which="LM", return_eigenvectors=False)
    times_scipy.append(time.perf_counter() - t0)
t_scipy = float(np.median(times_scipy))
rss_all = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
f_scipy = np.sort(np.sqrt(np.maximum(vals, 0)) / (2 * math.pi))
f_ours = np.array(ours["frequencies_hz"])
elastic = f_scipy > 1.0
rel = np.max(np.abs(f_ours[elastic] - f_scipy[elastic]) / f_scipy[elastic])

print(f"time ratio linercav (whole process) / SciPy eigsh (solve only): {t_ours / t_scipy:.3f}"
      f"  (speed-up {t_scipy / t_ours:.1f}x)")
print(f"largest relative difference of elastic frequencies: {rel:.2e}")
print(f"model: {' '.join(model[:3]) if a.scene else msh}, {ours['dofs']} DOFs, {a.count} modes, shift {ours['shift_hz']} Hz")
print(f"linercav: {t_ours:.2f} s wall (median of {' '.join(f'{t:.2f}' for t in times_ours)}), peak RSS {rss_ours:.2f} GB, Sturm check ok: {ours['sturm_count_ok']}"
      f", phases {json.dumps(ours['timings'])}")
print(f"SciPy {scipy.__version__} eigsh: {t_scipy:.1f} s (median of {' '.join(f'{t:.1f}' for t in times_scipy)}), peak RSS of the Python process {rss_all:.2f} GB")
