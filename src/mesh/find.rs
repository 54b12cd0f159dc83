//! Interfaces and analysis points found from the geometry of imported liner and crankcase
//! meshes, for decks that carry none of linercav's set names.
//!
//! Frames (those of the parametric generators, [`super::liner`], [`super::crankcase`]):
//! - the liner's own frame: z the bore axis, z = 0 at the liner bottom, the flange at the top;
//!   x, y as in the engine frame (thrust side +y);
//! - the engine frame: x along the crankshaft, cylinder c's bore axis at
//!   x_c = (c - (N + 1) / 2) p, y = 0, z up along the bores, thrust side +y.
//!
//! The liner ([`place_liner`]): its axis is first the principal axis of inertia of its nodes
//! whose moment stands apart from the other two (an axisymmetric body has two equal
//! transverse moments), then the bore's own axis: the line of centres of a cylinder fitted to
//! the bore's nodes (Kasa's linear fit with a sloping centre line, iterated), since an
//! unstructured or locally refined deck's node cloud is lopsided; an axis within 1e-12 of a
//! coordinate axis is taken as it. Its centre is the least-squares circle (Kasa fit: x^2 + y^2
//! = 2 a x + 2 b y + c) through the bore's nodes; its top the end with the larger radius (the
//! flange). The mesh is moved rigidly into the liner's frame:
//! p' = R (p - c) - z_min e_z, with R the smallest rotation taking the axis to +z.
//! Radii from the outer surface (boundary faces facing away from the axis, `outer_surface`)
//! as a profile of heights, each its largest radius: the flange starts at the highest face
//! facing down (`flange_underside`); the pilot r_p is the largest radius below the flange
//! (the guide band's and deck bore's on a stepped liner, which may differ); the wet wall r_o
//! is the radius over the greatest height below the flange (r_p = r_o on a plain tube); bore
//! r_i = min r, flange r_f = max r; the flange underside z_s = min z of the nodes with
//! r > r_p + tol.
//!
//! The crankcase ([`seat_crankcase`]): each bore's counterbore floor is the highest crankcase
//! node in the annulus r_o - tol <= r <= r_f - tol around the bore axis; the crankcase is moved
//! along z so that cylinder 1's floor meets the liner's flange underside, then across by less
//! than tol so that its bores' centres meet the frame's axes ([`centre_crankcase`]). The guide band is the
//! lowest z-band of the crankcase's bore surface r_o <= r <= r_p (element faces with at least
//! three corners there, [`LinerShape::holds`]) below the seat; the band that meets the seat (a
//! deck bore) is not coupled.
//!
//! Tolerance: tol = 0.02 h, h the median element edge of the part (its local mesh size): well
//! below a coolant gap and a wall, well above the roundoff of a deck's coordinates.

use super::Mesh;

/// Why an interface or point could not be found.
#[derive(Debug, thiserror::Error)]
#[error("{part}: {msg}")]
pub struct FindError {
    pub part: String,
    pub msg: String,
}

fn fail(part: &str, msg: String) -> FindError {
    FindError {
        part: part.into(),
        msg,
    }
}

/// The liner's shape in its own frame \[m\].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LinerShape {
    pub inner_radius: f64,
    pub outer_radius: f64,
    pub flange_radius: f64,
    /// Radius of the pilot surfaces (guide band, deck bore) where the crankcase holds the
    /// liner; the outer radius on an imported liner.
    pub pilot_radius: f64,
    pub length: f64,
    /// Height of the flange underside above the liner bottom.
    pub seat_z: f64,
    /// Tolerance of the liner's surfaces (0.02 of its median element edge).
    pub tol: f64,
}

impl LinerShape {
    /// Whether a crankcase surface at radius `r` about a bore axis can hold the liner there:
    /// r within `tol` of [r_o, r_p], the wet wall to the pilot (a stepped liner's guide band
    /// and deck bore are at its pilot radii, a plain tube's at r_o).
    pub fn holds(&self, r: f64, tol: f64) -> bool {
        r > self.outer_radius - tol && r < self.pilot_radius + tol
    }
}

/// How a set came to be: named in the deck, found from the geometry, or a scene box.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FoundSet {
    pub part: String,
    pub name: String,
    /// "deck", "geometry", "box" or "generator".
    pub source: String,
    pub nodes: usize,
    /// What was found: radii, heights, areas, distances [m, m^2].
    pub detail: String,
}

/// What was found on a pair of imported meshes, for the output and `rom --json`.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FoundInterfaces {
    pub liner: Option<LinerShape>,
    /// Rigid motion applied to the liner mesh: the axis found (deck frame) and the centre.
    pub liner_axis: Option<[f64; 3]>,
    pub liner_centre: Option<[f64; 3]>,
    /// Turn applied to the liner about its axis to bring a column of bore nodes onto the
    /// thrust line \[rad\].
    #[serde(default)]
    pub liner_turn: f64,
    /// z shift applied to the crankcase to seat cylinder 1's liner \[m\].
    pub crankcase_shift_z: f64,
    /// (x, y) shift applied to the crankcase to centre its bores on the liners' axes \[m\].
    #[serde(default)]
    pub crankcase_shift_xy: [f64; 2],
    /// Guide band [z0, z1] in the liner frame \[m\].
    pub guide_band: Option<[f64; 2]>,
    pub sets: Vec<FoundSet>,
    /// Which material each part used: "liner: scene" or "crankcase: deck (MAT1 1, MAT1 2)".
    pub materials: Vec<String>,
}

/// Median of the first corner edge of every element: the part's typical mesh size h \[m\].
pub fn mesh_size(mesh: &Mesh) -> f64 {
    let mut h: Vec<f64> = mesh
        .elements()
        .map(|(_, n)| dist(&mesh.nodes[n[0]], &mesh.nodes[n[1]]))
        .filter(|d| d.is_finite() && *d > 0.0)
        .collect();
    if h.is_empty() {
        return 0.0;
    }
    let k = h.len() / 2;
    let (_, m, _) = h.select_nth_unstable_by(k, |a, b| a.total_cmp(b));
    *m
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The principal axis of the nodes' second moments that stands apart from the other two.
fn principal_axis(nodes: &[[f64; 3]]) -> [f64; 3] {
    let n = nodes.len().max(1) as f64;
    let mut c = [0.0; 3];
    for p in nodes {
        for a in 0..3 {
            c[a] += p[a] / n;
        }
    }
    let mut cov = nalgebra::Matrix3::<f64>::zeros();
    for p in nodes {
        let d = nalgebra::Vector3::new(p[0] - c[0], p[1] - c[1], p[2] - c[2]);
        cov += d * d.transpose();
    }
    let eig = nalgebra::SymmetricEigen::new(cov);
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let l = idx.map(|i| eig.eigenvalues[i]);
    let pick = if l[2] - l[1] > l[1] - l[0] {
        idx[2]
    } else {
        idx[0]
    };
    let v = eig.eigenvectors.column(pick);
    let mut axis = [v[0], v[1], v[2]];
    for a in 0..3 {
        if axis[a].abs() > 1.0 - 1e-9 {
            axis = [0.0; 3];
            axis[a] = 1.0;
        }
    }
    axis
}

/// The axis `a` or -a, whichever points to the flange: the end (last 10 % of the length) whose
/// nodes lie farther from the axis through the nodes' mean.
fn toward_flange(nodes: &[[f64; 3]], a: [f64; 3], tol: f64) -> [f64; 3] {
    let n = nodes.len().max(1) as f64;
    let c = [0, 1, 2].map(|k| nodes.iter().map(|p| p[k]).sum::<f64>() / n);
    let proj = |p: &[f64; 3]| -> (f64, f64) {
        let d = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
        let t = d[0] * a[0] + d[1] * a[1] + d[2] * a[2];
        let r2 = d.iter().map(|x| x * x).sum::<f64>() - t * t;
        (t, r2.max(0.0).sqrt())
    };
    let (lo, hi) = nodes
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            let t = proj(p).0;
            (lo.min(t), hi.max(t))
        });
    let span = hi - lo;
    let rmax = |near_hi: bool| {
        nodes
            .iter()
            .map(proj)
            .filter(|(t, _)| {
                if near_hi {
                    *t > hi - 0.1 * span
                } else {
                    *t < lo + 0.1 * span
                }
            })
            .map(|(_, r)| r)
            .fold(0.0, f64::max)
    };
    if rmax(false) > rmax(true) + tol {
        a.map(|v| -v)
    } else {
        a
    }
}

/// The rotation R (rows) taking unit vector `a` to +z: Rodrigues about a x e_z; a half turn
/// about x when a = -z.
fn rotation_to_z(a: [f64; 3]) -> [[f64; 3]; 3] {
    let c = a[2];
    if c > 1.0 - 1e-15 {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    if c < -1.0 + 1e-15 {
        return [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]];
    }
    // k = a x e_z = (a_y, -a_x, 0), |k| = sin(theta); R = I + [k]x + [k]x^2 / (1 + c)
    let (kx, ky) = (a[1], -a[0]);
    let f = 1.0 / (1.0 + c);
    [
        [1.0 - f * ky * ky, f * kx * ky, ky],
        [f * kx * ky, 1.0 - f * kx * kx, -kx],
        [-ky, kx, c],
    ]
}

fn apply(r: &[[f64; 3]; 3], p: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| r[i][0] * p[0] + r[i][1] * p[1] + r[i][2] * p[2])
}

/// Least-squares circle through points (x, y): (centre, radius), Kasa's linear fit.
fn circle_fit(pts: &[[f64; 2]]) -> Option<([f64; 2], f64)> {
    let mut a = nalgebra::Matrix3::<f64>::zeros();
    let mut b = nalgebra::Vector3::<f64>::zeros();
    for p in pts {
        let row = nalgebra::Vector3::new(2.0 * p[0], 2.0 * p[1], 1.0);
        a += row * row.transpose();
        b += row * (p[0] * p[0] + p[1] * p[1]);
    }
    let s = a.lu().solve(&b)?;
    let r2 = s[2] + s[0] * s[0] + s[1] * s[1];
    (r2 > 0.0).then(|| ([s[0], s[1]], r2.sqrt()))
}

/// The bore's centre (x, y) in the frame of `pts` (turned so that the axis is about z):
/// Kasa's circle through the nodes within h / 4 of the smallest radius, refined three times
/// from the nodes' mean, then fitted again without the nodes off it by more than `tol`.
fn bore_centre(pts: &[[f64; 3]], h: f64, tol: f64) -> [f64; 2] {
    let n = pts.len() as f64;
    let mut c = [0, 1].map(|a| pts.iter().map(|p| p[a]).sum::<f64>() / n);
    let mut last = None;
    for _ in 0..3 {
        let r = |p: &[f64; 3]| (p[0] - c[0]).hypot(p[1] - c[1]);
        let rmin = pts.iter().map(r).fold(f64::INFINITY, f64::min);
        let bore: Vec<[f64; 2]> = pts
            .iter()
            .filter(|p| r(p) < rmin + 0.25 * h)
            .map(|p| [p[0], p[1]])
            .collect();
        if let Some((cc, radius)) = circle_fit(&bore) {
            c = cc;
            last = Some((bore, radius));
        }
    }
    // once more without the nodes off the circle by more than tol (a recess on one side),
    // when at least half stay
    let Some((bore, radius)) = last else {
        return c;
    };
    let on: Vec<[f64; 2]> = bore
        .iter()
        .filter(|p| ((p[0] - c[0]).hypot(p[1] - c[1]) - radius).abs() <= tol)
        .copied()
        .collect();
    match circle_fit(&on) {
        Some((trimmed, _)) if on.len() < bore.len() && 2 * on.len() >= bore.len() => trimmed,
        _ => c,
    }
}

/// The bore's nodes of `pts` (turned so that the axis is about z, centre `c`): those within
/// h / 4 of the smallest radius among the nodes of their slab (height 2h) and the two slabs
/// either side. Slabs keep a tilted axis from hiding one end of the bore; the neighbours keep
/// a slab that holds no bore node (a node layer pushed across a slab's edge) from offering
/// its outer wall.
fn bore_nodes(pts: &[[f64; 3]], c: [f64; 2], h: f64) -> Vec<[f64; 3]> {
    let zmin = pts.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
    let slab = |p: &[f64; 3]| ((p[2] - zmin) / (2.0 * h)) as usize;
    let r = |p: &[f64; 3]| (p[0] - c[0]).hypot(p[1] - c[1]);
    let slabs = pts.iter().map(slab).max().unwrap_or(0) + 1;
    let mut own = vec![f64::INFINITY; slabs];
    for p in pts {
        let k = slab(p);
        own[k] = own[k].min(r(p));
    }
    let near: Vec<f64> = (0..slabs)
        .map(|k| {
            own[k.saturating_sub(2)..(k + 3).min(slabs)]
                .iter()
                .fold(f64::INFINITY, |a, &b| a.min(b))
        })
        .collect();
    pts.iter()
        .filter(|p| r(p) < near[slab(p)] + 0.25 * h)
        .copied()
        .collect()
}

/// The tilt (t_x, t_y) of the bore's axis in the frame of its nodes `bore`: the line of
/// centres (a + t_x z, b + t_y z) of Kasa's circle extended to a sloping centre line, linear
/// least squares of
/// x^2 + y^2 = 2a x + 2b y + 2 t_x x z + 2 t_y y z + e + f z + g z^2
/// (exact for circular sections; a right cylinder tilted by theta has elliptic ones, axes r
/// and r / cos theta, an error of order theta^2 that iterating removes). Coordinates are
/// taken about the nodes' mean and scaled by their spread for the normal equations. The fit
/// is made again without the nodes off its surface by more than `tol` (a residual rho^2 -
/// fit is 2 rho times the distance), when at least half the nodes stay: a recess, a groove
/// or a port on one side of the bore tilted the axis (0.2 mm deep on 9 nodes of 2528: 4e-5
/// rad, the bore measured 10 um small, exit 0).
fn bore_tilt(bore: &[[f64; 3]], tol: f64) -> Option<[f64; 2]> {
    let n = bore.len() as f64;
    let m = [0, 1, 2].map(|a| bore.iter().map(|p| p[a]).sum::<f64>() / n);
    let s = bore
        .iter()
        .flat_map(|p| (0..3).map(move |a| (p[a] - m[a]).abs()))
        .fold(0.0, f64::max);
    if s.is_nan() || s <= 0.0 {
        return None;
    }
    let scaled: Vec<[f64; 3]> = bore
        .iter()
        .map(|p| [0, 1, 2].map(|k| (p[k] - m[k]) / s))
        .collect();
    let row = |&[x, y, z]: &[f64; 3]| {
        nalgebra::SVector::<f64, 7>::from([x, y, x * z, y * z, 1.0, z, z * z])
    };
    let fit = |keep: &dyn Fn(&[f64; 3]) -> bool| {
        let mut a = nalgebra::SMatrix::<f64, 7, 7>::zeros();
        let mut b = nalgebra::SVector::<f64, 7>::zeros();
        for p in scaled.iter().filter(|p| keep(p)) {
            let r = row(p);
            a += r * r.transpose();
            b += r * (p[0] * p[0] + p[1] * p[1]);
        }
        a.cholesky().map(|c| c.solve(&b))
    };
    let mut sol = fit(&|_| true)?;
    let off = |sol: &nalgebra::SVector<f64, 7>, p: &[f64; 3]| {
        let rho2 = p[0] * p[0] + p[1] * p[1];
        (rho2 - row(p).dot(sol)).abs() * s / (2.0 * rho2.sqrt().max(f64::MIN_POSITIVE)) > tol
    };
    let outliers = scaled.iter().filter(|p| off(&sol, p)).count();
    if outliers > 0 && 2 * outliers <= scaled.len() {
        let first = sol;
        sol = fit(&|p| !off(&first, p))?;
    }
    // 2 t_x = coefficient of x z; z scaled like x, so the slope is scale-free
    let t = [0.5 * sol[2], 0.5 * sol[3]];
    t.iter().all(|v| v.is_finite()).then_some(t)
}

/// The liner's axis pointing to the flange: the principal axis of its nodes (turned toward
/// the flange), then the bore's own axis ([`bore_tilt`], iterated until it moves less than
/// 1e-14 rad): an unstructured or locally refined deck's node cloud is not symmetric, and
/// its principal axis may tilt by 1e-4 rad or more. An axis within 1e-12 of a coordinate
/// axis is taken as that axis.
fn liner_axis(nodes: &[[f64; 3]], h: f64, tol: f64) -> [f64; 3] {
    let mut axis = toward_flange(nodes, principal_axis(nodes), tol);
    for _ in 0..6 {
        let rot = rotation_to_z(axis);
        let pts: Vec<[f64; 3]> = nodes.iter().map(|&p| apply(&rot, p)).collect();
        let c = bore_centre(&pts, h, tol);
        let Some(t) = bore_tilt(&bore_nodes(&pts, c, h), tol) else {
            break;
        };
        let k = 1.0 / (1.0 + t[0] * t[0] + t[1] * t[1]).sqrt();
        let d = [t[0] * k, t[1] * k, k];
        // R^T d: back to the deck's frame
        let next = [0, 1, 2].map(|i| (0..3).map(|j| rot[j][i] * d[j]).sum::<f64>());
        let moved = (0..3).map(|i| (next[i] - axis[i]).powi(2)).sum::<f64>();
        axis = next;
        if moved.sqrt() < 1e-14 {
            break;
        }
    }
    for a in 0..3 {
        let off = (0..3)
            .filter(|&b| b != a)
            .map(|b| axis[b].abs())
            .fold(0.0, f64::max);
        if off < 1e-12 {
            let sign = axis[a].signum();
            axis = [0.0; 3];
            axis[a] = sign;
        }
    }
    axis
}

/// Moves a liner mesh into its own frame and measures it (module docs). Returns the shape,
/// the axis found and the centre of the bottom.
pub fn place_liner(mesh: &mut Mesh) -> Result<(LinerShape, [f64; 3], [f64; 3]), FindError> {
    let h = mesh_size(mesh);
    if mesh.nodes.len() < 8 || h <= 0.0 {
        return Err(fail("liner", "too few nodes to find its axis".into()));
    }
    let tol = 0.02 * h;
    let axis = liner_axis(&mesh.nodes, h, tol);
    let rot = rotation_to_z(axis);
    let mut pts: Vec<[f64; 3]> = mesh.nodes.iter().map(|&p| apply(&rot, p)).collect();
    let c = bore_centre(&pts, h, tol);
    let zmin = pts.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
    for p in &mut pts {
        *p = [p[0] - c[0], p[1] - c[1], p[2] - zmin];
    }
    let centre_deck = {
        // the bottom centre in the deck's frame: R^T (c, zmin) for the unflipped frame
        let q = [c[0], c[1], zmin];
        [0, 1, 2].map(|i| rot[0][i] * q[0] + rot[1][i] * q[1] + rot[2][i] * q[2])
    };
    mesh.nodes = pts;
    let shape = measure_liner(mesh, tol)?;
    Ok((shape, axis, centre_deck))
}

/// Turns a placed liner (own frame, shape `s`) about its axis so that a column of its bore's
/// nodes lies on the thrust line (x = 0, y > 0), when none does and the column nearest to the
/// line holds at least three nodes: a structured deck turned about its axis then has its
/// thrust and anti-thrust lines as the generator's (without, they were empty, or widened to
/// nodes 5 mm off the line). The liner is axisymmetric: the turn moves no surface. An
/// unstructured deck (no column of three) is left as it is. Returns the turn \[rad\]: a
/// column at angle phi from +y toward +x is turned by +phi, (x, y) -> (x cos phi - y sin phi,
/// x sin phi + y cos phi).
pub fn turn_liner_to_thrust_line(mesh: &mut Mesh, s: &LinerShape) -> f64 {
    let tol = s.tol;
    let bore: Vec<[f64; 2]> = mesh
        .nodes
        .iter()
        .filter(|p| (p[0].hypot(p[1]) - s.inner_radius).abs() < tol && p[1] > 0.0)
        .map(|p| [p[0], p[1]])
        .collect();
    if bore.iter().filter(|p| p[0].abs() < tol).count() >= 3 {
        return 0.0;
    }
    let angle = |p: &[f64; 2]| p[0].atan2(p[1]);
    let Some(phi) = bore
        .iter()
        .map(angle)
        .min_by(|a, b| a.abs().total_cmp(&b.abs()))
    else {
        return 0.0;
    };
    let column = bore
        .iter()
        .filter(|p| (angle(p) - phi).abs() * s.inner_radius < tol)
        .count();
    if column < 3 {
        return 0.0;
    }
    let (sn, cs) = phi.sin_cos();
    for p in &mut mesh.nodes {
        *p = [p[0] * cs - p[1] * sn, p[0] * sn + p[1] * cs, p[2]];
    }
    phi
}

/// Radii and heights of a liner in its own frame (module docs).
fn measure_liner(mesh: &Mesh, tol: f64) -> Result<LinerShape, FindError> {
    let r = |p: &[f64; 3]| p[0].hypot(p[1]);
    let length = mesh.nodes.iter().map(|p| p[2]).fold(0.0, f64::max);
    let inner = mesh.nodes.iter().map(r).fold(f64::INFINITY, f64::min);
    // the middle's largest radius: the wet wall, or a pilot there; it only splits the bore's
    // faces from the outer ones
    let middle = mesh
        .nodes
        .iter()
        .filter(|p| p[2] > 0.3 * length && p[2] < 0.7 * length)
        .map(r)
        .fold(0.0, f64::max);
    let flange = mesh.nodes.iter().map(r).fold(0.0, f64::max);
    if !(inner > 0.0 && middle > inner + tol) {
        return Err(fail(
            "liner",
            format!("no tube found: bore radius {inner:.6} m, outer radius {middle:.6} m"),
        ));
    }
    let no_flange = || {
        let mm = |v: f64| crate::text::num(v * 1e3);
        fail(
            "liner",
            format!(
                "no top flange found: no outer surface stands out of the wall (bore radius {} mm, largest radius {} mm, surfaces taken to {} mm, 0.02 of the median element edge): a deck that is not a flanged tube, or whose surfaces scatter more than that; name the set 'flange_seat' in the deck",
                mm(inner),
                mm(flange),
                mm(tol)
            ),
        )
    };
    let mid = 0.5 * (inner + middle);
    let surface = outer_surface(mesh, mid);
    let levels = surface_levels(mesh, &surface, tol);
    let underside = flange_underside(mesh, mid);
    let (wall, pilot) = below_flange(&levels, underside, tol).ok_or_else(no_flange)?;
    let seat_z = mesh
        .nodes
        .iter()
        .filter(|p| r(p) > pilot + tol)
        .map(|p| p[2])
        .fold(f64::INFINITY, f64::min);
    if flange <= pilot + tol || !seat_z.is_finite() {
        return Err(no_flange());
    }
    Ok(LinerShape {
        inner_radius: inner,
        outer_radius: wall,
        flange_radius: flange,
        pilot_radius: pilot,
        length,
        seat_z,
        tol,
    })
}

/// The nodes on the liner's outer surface (own frame): those of boundary faces (faces of one
/// element only) that face away from the axis, |n . e_r| >= |n| / 2 at the face's centre,
/// with the centre beyond `mid` (the wall's middle radius: the bore's faces are not taken),
/// mid-edge nodes of quadratic faces included. A stepped liner's pilots, its tapers and its
/// flange rim are on it, its flange and shoulder faces (normal along z) are not.
fn outer_surface(mesh: &Mesh, mid: f64) -> Vec<bool> {
    let mut on = vec![false; mesh.nodes.len()];
    for_boundary_faces(mesh, &mut |kind, el, face, c| {
        let [n, m] = normal_and_centre(c);
        let (nn, rm) = (norm(n), m[0].hypot(m[1]));
        let nr = (n[0] * m[0] + n[1] * m[1]) / rm.max(f64::MIN_POSITIVE);
        if !(rm > mid && nr.abs() >= 0.5 * nn && nn > 0.0) {
            return;
        }
        for &a in face {
            on[el[a]] = true;
        }
        for (k, &(a, b)) in kind.mid_edges().iter().enumerate() {
            if face.contains(&a) && face.contains(&b) {
                on[el[kind.num_corners() + k]] = true;
            }
        }
    });
    on
}

/// The height of a liner's flange underside (own frame): the highest boundary face facing
/// down (outward normal n_z <= -0.9 |n|, within 26 deg of -z) whose centre lies beyond the
/// radius `mid`. A pilot's shoulder, an O-ring groove's wall and the bottom face are lower; a
/// fillet or flare under the flange faces outward, not down. None: no such face.
fn flange_underside(mesh: &Mesh, mid: f64) -> Option<f64> {
    let mut top = f64::NEG_INFINITY;
    for_boundary_faces(mesh, &mut |_, _, _, c| {
        let [n, m] = normal_and_centre(c);
        if m[0].hypot(m[1]) > mid && n[2] <= -0.9 * norm(n) && norm(n) > 0.0 {
            top = top.max(m[2]);
        }
    });
    top.is_finite().then_some(top)
}

/// A visitor of boundary faces: (element kind, element nodes, face corners in element
/// numbering, the corners' coordinates).
type FaceVisitor<'v> =
    dyn FnMut(crate::scene::spec::ElementKind, &[usize], &[usize], &[[f64; 3]]) + 'v;

/// Calls `f` for every boundary face (a face of one element only) of `mesh`.
fn for_boundary_faces(mesh: &Mesh, f: &mut FaceVisitor<'_>) {
    use std::collections::hash_map::Entry;
    // each face once, in the elements' order, with the number of elements that hold it
    let mut index: std::collections::HashMap<Vec<usize>, usize> = Default::default();
    let mut faces = Vec::new();
    for (kind, el) in mesh.elements() {
        for &face in kind.faces() {
            let mut key: Vec<usize> = face.iter().map(|&a| el[a]).collect();
            key.sort_unstable();
            match index.entry(key) {
                Entry::Occupied(e) => faces[*e.get()] = None,
                Entry::Vacant(e) => {
                    e.insert(faces.len());
                    faces.push(Some((kind, el, face)));
                }
            }
        }
    }
    for (kind, el, face) in faces.into_iter().flatten() {
        let c: Vec<[f64; 3]> = face.iter().map(|&a| mesh.nodes[el[a]]).collect();
        f(kind, el, face, &c);
    }
}

/// The liner's outer wall below its flange (`s`, own frame): the [`outer_surface`] nodes
/// within the pilot radius and at most the seat's height (wet wall, pilots, tapers).
fn wall_surface(mesh: &Mesh, s: &LinerShape) -> Vec<bool> {
    let mid = 0.5 * (s.inner_radius + s.outer_radius);
    let mut on = outer_surface(mesh, mid);
    for (n, p) in mesh.nodes.iter().enumerate() {
        on[n] &= p[0].hypot(p[1]) < s.pilot_radius + s.tol && p[2] < s.seat_z + s.tol;
    }
    on
}

/// A face's outward normal n (the cross product of its diagonals, or of two edges of a
/// triangle: corners in the right-hand order of [`ElementKind::faces`], |n| ~ its area) and
/// its centre (the corners' mean); zeros for another corner count.
///
/// [`ElementKind::faces`]: crate::scene::spec::ElementKind::faces
fn normal_and_centre(c: &[[f64; 3]]) -> [[f64; 3]; 2] {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let (u, v) = match c {
        [a, b, d] => (sub(*b, *a), sub(*d, *a)),
        [a, b, d, e] => (sub(*d, *a), sub(*e, *b)),
        _ => return [[0.0; 3]; 2],
    };
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let k = c.len() as f64;
    [
        n,
        [0, 1, 2].map(|i| c.iter().map(|p| p[i]).sum::<f64>() / k),
    ]
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The heights of the liner's outer surface (`surface`), bottom to top: [z, r], the nodes
/// within `tol` in z one level, its radius the largest there.
fn surface_levels(mesh: &Mesh, surface: &[bool], tol: f64) -> Vec<[f64; 2]> {
    let mut pts: Vec<[f64; 2]> = (0..mesh.nodes.len())
        .filter(|&n| surface[n])
        .map(|n| {
            let p = mesh.nodes[n];
            [p[2], p[0].hypot(p[1])]
        })
        .collect();
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let mut levels: Vec<[f64; 2]> = Vec::new();
    for [z, r] in pts {
        match levels.last_mut() {
            Some(l) if z - l[0] < tol => l[1] = l[1].max(r),
            _ => levels.push([z, r]),
        }
    }
    levels
}

/// The wet wall's radius r_o and the largest radius r_p below the flange (the pilot of a
/// stepped liner, r_o on a plain tube), from the outer surface's `levels`. The flange starts
/// at its `underside` ([`flange_underside`]) when found, else it is the top run of levels each
/// wider, by more than `tol`, than every level below it (a stepped liner whose upper pilot is
/// wider than its lower one needs the underside: its upper pilot is such a run). The wet wall
/// is the radius (within `tol`) over the greatest height below the flange: each level
/// counts half of the gaps to its neighbours. None: no flange.
fn below_flange(levels: &[[f64; 2]], underside: Option<f64>, tol: f64) -> Option<(f64, f64)> {
    let mut above = vec![f64::INFINITY; levels.len() + 1];
    for i in (0..levels.len()).rev() {
        above[i] = above[i + 1].min(levels[i][1]);
    }
    // widest[i]: the largest radius of the levels below level i
    let mut widest = vec![f64::NEG_INFINITY; levels.len() + 1];
    for i in 0..levels.len() {
        widest[i + 1] = widest[i].max(levels[i][1]);
    }
    let seat = match underside {
        Some(z) => (1..levels.len()).find(|&i| levels[i][0] > z - tol)?,
        None => (1..levels.len()).find(|&i| above[i] > widest[i] + tol)?,
    };
    let pilot = widest[seat];
    let mut heights: Vec<[f64; 2]> = (0..seat)
        .map(|i| {
            let lo = levels[i.saturating_sub(1)][0];
            let hi = levels[i + 1][0];
            [levels[i][1], 0.5 * (hi - lo)]
        })
        .collect();
    heights.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let mut best = [0.0, f64::NEG_INFINITY];
    let mut k = 0;
    while k < heights.len() {
        let group: Vec<[f64; 2]> = heights[k..]
            .iter()
            .take_while(|h| h[0] < heights[k][0] + tol)
            .copied()
            .collect();
        let height: f64 = group.iter().map(|h| h[1]).sum();
        if height > best[1] {
            best = [group[group.len() - 1][0], height];
        }
        k += group.len();
    }
    Some((best[0], pilot))
}

/// The analysis-point and band inputs of the liner's sets.
pub struct LinerTargets<'a> {
    /// Guide band [z0, z1] in the liner frame \[m\].
    pub guide: [f64; 2],
    /// Depths of the analysis points below the liner top \[m\].
    pub depths: &'a [f64],
}

/// Adds to a liner in its own frame the sets the later stages use that it does not name
/// (sets named in the deck win); returns what each set is and where it came from.
pub fn liner_sets(mesh: &mut Mesh, s: &LinerShape, t: &LinerTargets<'_>) -> Vec<FoundSet> {
    let tol = s.tol;
    let r = |p: &[f64; 3]| p[0].hypot(p[1]);
    let outer = wall_surface(mesh, s);
    let on_outer = |n: usize| outer[n];
    let thrust = |p: &[f64; 3], sign: f64| p[0].abs() < tol && sign * p[1] > 0.0;
    let [g0, g1] = t.guide;
    let pi = std::f64::consts::PI;
    let (ro, rf) = (s.outer_radius, s.flange_radius);
    type Pred<'p> = Box<dyn Fn(usize, &[f64; 3]) -> bool + 'p>;
    let rules: Vec<(String, Pred<'_>, String)> = vec![
        (
            "flange_seat".into(),
            Box::new(|_, p| (p[2] - s.seat_z).abs() < tol && r(p) > ro - tol),
            format!(
                "z = {:.6} m, r {:.6}..{:.6} m, area {:.4e} m^2",
                s.seat_z,
                ro,
                rf,
                pi * (rf * rf - ro * ro)
            ),
        ),
        (
            "flange_top".into(),
            Box::new(|_, p| (p[2] - s.length).abs() < tol && r(p) > ro - tol),
            format!("z = {:.6} m", s.length),
        ),
        (
            "lower_guide".into(),
            Box::new(move |n, p| on_outer(n) && p[2] > g0 - tol && p[2] < g1 + tol),
            format!(
                "r = {:.6} m, z {g0:.6}..{g1:.6} m, area {:.4e} m^2",
                s.pilot_radius,
                2.0 * pi * s.pilot_radius * (g1 - g0)
            ),
        ),
        (
            "bore_thrust".into(),
            Box::new(|_, p| (r(p) - s.inner_radius).abs() < tol && thrust(p, 1.0)),
            format!("r = {:.6} m, +y", s.inner_radius),
        ),
        (
            "bore_antithrust".into(),
            Box::new(|_, p| (r(p) - s.inner_radius).abs() < tol && thrust(p, -1.0)),
            format!("r = {:.6} m, -y", s.inner_radius),
        ),
        (
            "outer_thrust".into(),
            Box::new(|n, p| on_outer(n) && thrust(p, 1.0)),
            format!("r = {ro:.6} m, +y, z <= {:.6} m", s.seat_z),
        ),
        (
            super::liner::COOLANT_WETTED.into(),
            Box::new(move |n, p| on_outer(n) && p[2] > g1 - tol),
            format!(
                "r = {ro:.6} m, z {g1:.6}..{:.6} m, area {:.4e} m^2",
                s.seat_z,
                2.0 * pi * ro * (s.seat_z - g1)
            ),
        ),
    ];
    let mut out = Vec::new();
    for (name, pred, detail) in rules {
        out.push(add_set(mesh, "liner", &name, &*pred, detail));
    }
    for (k, &d) in t.depths.iter().enumerate() {
        let target = [0.0, ro, s.length - d];
        let name = format!("point_{}", k + 1);
        // on the wet wall: a pilot's corner nearer the depth is not wetted
        let wet = |n: usize, p: &[f64; 3]| on_outer(n) && (r(p) - ro).abs() < tol;
        out.push(add_point(mesh, "liner", &name, target, &wet));
        warn_point_off(mesh, &out[out.len() - 1], (k, d), s);
    }
    let h = s.tol / 0.02;
    let on_bore = |_: usize, p: &[f64; 3]| (r(p) - s.inner_radius).abs() < tol;
    for (name, on, sign) in [
        (
            "bore_thrust",
            &on_bore as &dyn Fn(usize, &[f64; 3]) -> bool,
            1.0,
        ),
        ("bore_antithrust", &on_bore, -1.0),
        ("outer_thrust", &|n, _| on_outer(n), 1.0),
    ] {
        widen_line(mesh, &mut out, name, on, sign, h);
    }
    for name in ["bore_thrust", "bore_antithrust", "outer_thrust"] {
        let nodes = &mesh.nodes;
        if let Some(v) = mesh.node_sets.get_mut(name) {
            v.sort_by(|&a, &b| nodes[a][2].total_cmp(&nodes[b][2]));
        }
    }
    out
}

/// Warns of an analysis point found (`f`, the set `point_<k+1>`) more than one element (the
/// median edge h) from its depth `d` below the liner top: a deck coarse along the axis
/// (a crowded one put them 7.3 mm off without a word) reports the response at the node found,
/// not at the scene's depth (the rule [`check_liner_deck_sets`] applies to a deck's own
/// points).
fn warn_point_off(mesh: &Mesh, f: &FoundSet, (k, d): (usize, f64), s: &LinerShape) {
    let Some(&[n]) = mesh.node_sets.get(&f.name).map(|v| &v[..]) else {
        return;
    };
    if f.source != "geometry" {
        return;
    }
    let depth = s.length - mesh.nodes[n][2];
    let h = s.tol / 0.02;
    if (depth - d).abs() > h {
        crate::text::warn(format!(
            "liner: analysis point {} found {} mm below the liner top, its nearest node on the wet wall's thrust side, against the {} mm the scene's liner.analysis_first_depth_mm and liner.analysis_spacing_mm give (more than the deck's median element edge, {} mm): reported at that node; refine the deck along the axis there or name the set {}",
            k + 1,
            crate::text::num(depth * 1e3),
            crate::text::num(d * 1e3),
            crate::text::num(h * 1e3),
            f.name
        ));
    }
}

/// Checks the liner deck's own line and point sets (`found`: where each set came from) in the
/// liner's frame against what they stand for, since they are taken as given: the bore lines
/// `bore_thrust` / `bore_antithrust` on the bore r_i on the thrust (+y) / anti-thrust (-y)
/// side and `outer_thrust` on the outer wall r_o on +y, every node (within the shape's
/// tolerance, |x| not checked: a deck's line may run beside the thrust line); each `point_k`
/// one node on the outer wall on +y. Refused otherwise: the contact forces would act on the
/// wrong side (a deck with the bore lines swapped changed every peak without a word), or a
/// point would report another node's response. A point more than one element (the median
/// edge) from the scene's depth for it is warned of: reported at the deck's node, not at the
/// depth the scene's `liner.analysis_*` keys give.
pub fn check_liner_deck_sets(
    mesh: &Mesh,
    s: &LinerShape,
    t: &LinerTargets<'_>,
    found: &[FoundSet],
) -> Result<(), FindError> {
    let from_deck = |name: &str| found.iter().any(|f| f.name == name && f.source == "deck");
    let (tol, h) = (s.tol, s.tol / 0.02);
    let r = |p: &[f64; 3]| p[0].hypot(p[1]);
    let lines = [
        (
            "bore_thrust",
            s.inner_radius,
            1.0,
            "the bore, thrust side (+y)",
        ),
        (
            "bore_antithrust",
            s.inner_radius,
            -1.0,
            "the bore, anti-thrust side (-y)",
        ),
        (
            "outer_thrust",
            s.outer_radius,
            1.0,
            "the outer wall, thrust side (+y)",
        ),
    ];
    let at = |n: usize| {
        let p = mesh.nodes[n];
        format!("the node at ({:.6}, {:.6}, {:.6}) m", p[0], p[1], p[2])
    };
    for (name, radius, sign, what) in lines.into_iter().filter(|l| from_deck(l.0)) {
        let nodes = mesh.node_sets.get(name).map_or(&[][..], |v| &v[..]);
        if let Some(&n) = nodes.iter().find(|&&n| {
            let p = &mesh.nodes[n];
            let off = if name == "outer_thrust" {
                !s.holds(r(p), tol)
            } else {
                (r(p) - radius).abs() >= tol
            };
            off || sign * p[1] <= 0.0
        }) {
            return Err(fail("liner", format!("the deck's set '{name}' must lie on {what} at r = {radius:.6} m in the liner's frame (its own x, y; thrust side +y): {} is not there; name the sets for this frame", at(n))));
        }
    }
    for (k, &d) in t.depths.iter().enumerate() {
        let name = format!("point_{}", k + 1);
        if !from_deck(&name) {
            continue;
        }
        let nodes = mesh.node_sets.get(&name).map_or(&[][..], |v| &v[..]);
        let &[n] = nodes else {
            return Err(fail("liner", format!("the deck's set '{name}' holds {} nodes: an analysis point is one node on the outer wall", nodes.len())));
        };
        let p = mesh.nodes[n];
        if (r(&p) - s.outer_radius).abs() >= tol || p[1] <= 0.0 {
            return Err(fail("liner", format!("the deck's set '{name}' must be a node of the outer (coolant) wall r = {:.6} m on the thrust side (+y) in the liner's frame: {} is not", s.outer_radius, at(n))));
        }
        let depth = s.length - p[2];
        if (depth - d).abs() > h {
            crate::text::warn(format!(
                "liner deck: the set '{name}' lies {} mm below the liner top, the scene's liner.analysis_first_depth_mm and liner.analysis_spacing_mm put point {} at {} mm: reported at the deck's node",
                crate::text::num(depth * 1e3),
                k + 1,
                crate::text::num(d * 1e3)
            ));
        }
    }
    Ok(())
}

/// Narrows a found `lower_guide` (`found`: where each set came from) to the nodes where the
/// liner's outer surface meets the guide bore: within `tol` (the liner's) of the set's largest radius (an
/// O-ring groove's floor and a wet wall the band reaches are left out: a crankcase guide bore
/// 20 mm longer than a stepped liner's pilot glued the wet wall across a 2.5 mm gap, +1.9 %
/// on a frequency, exit 0). Returns the z-range of the pilot there: the nodes kept, widened by
/// the element faces on the pilot's radius that reach them (`radius_spans`: a pilot runs on
/// between node rows; a deck whose rows missed the guide's top by 0.24 mm was narrowed to its
/// row below and refused for conditioning); None when the deck names the set or it is empty.
pub fn trim_lower_guide(mesh: &mut Mesh, found: &mut [FoundSet], tol: f64) -> Option<[f64; 2]> {
    let f = found
        .iter_mut()
        .find(|f| f.name == "lower_guide" && f.source == "geometry")?;
    let nodes = &mesh.nodes;
    let r = |n: usize| nodes[n][0].hypot(nodes[n][1]);
    let set = mesh.node_sets.get("lower_guide")?;
    let top = set.iter().map(|&n| r(n)).fold(f64::NEG_INFINITY, f64::max);
    let kept: Vec<usize> = set.iter().copied().filter(|&n| r(n) > top - tol).collect();
    let z = kept.iter().map(|&n| mesh.nodes[n][2]);
    let mut band = [
        z.clone().fold(f64::INFINITY, f64::min),
        z.fold(f64::NEG_INFINITY, f64::max),
    ];
    for sp in radius_spans(mesh, top, tol) {
        if sp[1] > band[0] - tol && sp[0] < band[1] + tol {
            band = [band[0].min(sp[0]), band[1].max(sp[1])];
        }
    }
    f.nodes = kept.len();
    mesh.node_sets.insert("lower_guide".into(), kept);
    band[0].is_finite().then_some(band)
}

/// The z-spans, bottom to top and merged where they meet, of the liner's element faces on the
/// radius `radius` (within `tol`; faces as [`bore_bands`] takes the crankcase's).
fn radius_spans(mesh: &Mesh, radius: f64, tol: f64) -> Vec<[f64; 2]> {
    let on = |p: &[f64; 3]| (p[0].hypot(p[1]) - radius).abs() < tol;
    merge_spans(face_spans(mesh, on).collect(), tol)
}

/// The z-extent [lo, hi] of every element face with three corners or more where `on` holds.
fn face_spans<'a>(
    mesh: &'a Mesh,
    on: impl Fn(&[f64; 3]) -> bool + 'a,
) -> impl Iterator<Item = [f64; 2]> + 'a {
    mesh.elements().filter_map(move |(kind, nodes)| {
        let z: Vec<f64> = nodes[..kind.num_corners()]
            .iter()
            .map(|&n| &mesh.nodes[n])
            .filter(|p| on(p))
            .map(|p| p[2])
            .collect();
        (z.len() >= 3).then(|| {
            let lo = z.iter().copied().fold(f64::INFINITY, f64::min);
            [lo, z.iter().copied().fold(f64::NEG_INFINITY, f64::max)]
        })
    })
}

/// `spans` sorted by their bottoms, those that meet (within `tol`) merged.
fn merge_spans(mut spans: Vec<[f64; 2]>, tol: f64) -> Vec<[f64; 2]> {
    spans.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let mut merged: Vec<[f64; 2]> = Vec::new();
    for sp in spans {
        match merged.last_mut() {
            Some(m) if sp[0] <= m[1] + tol => m[1] = m[1].max(sp[1]),
            _ => merged.push(sp),
        }
    }
    merged
}

/// Keeps of each crankcase set `guide_1` .. `guide_<cylinders>` the nodes within `band`
/// (within the part's tolerance), updating their counts in `found`.
pub fn narrow_guides(cm: &mut Mesh, cylinders: usize, band: [f64; 2], found: &mut [FoundSet]) {
    let tol = 0.02 * mesh_size(cm);
    for k in 1..=cylinders {
        let name = format!("guide_{k}");
        let nodes = &cm.nodes;
        let Some(set) = cm.node_sets.get(&name) else {
            continue;
        };
        let kept: Vec<usize> = set
            .iter()
            .copied()
            .filter(|&n| nodes[n][2] > band[0] - tol && nodes[n][2] < band[1] + tol)
            .collect();
        if let Some(f) = found.iter_mut().find(|f| f.name == name) {
            f.nodes = kept.len();
        }
        cm.node_sets.insert(name, kept);
    }
}

/// A line set is kept as found (the nodes within tol of the thrust line) when it covers its
/// surface: three nodes or more, no gap along z between them, or between the surface's ends
/// and them, wider than [`LINE_GAP`] h. Otherwise (an unstructured mesh has no nodes on the
/// line but strays) it is widened: the surface nodes within w = h/2 of the line, at each height
/// the one nearest to it; w doubled up to 2h while that does not cover (a coarse deck turned
/// about its axis: bore nodes 5.6 mm apart around, none within 2.5 mm of the line; the set was
/// empty, exit 2 without a cause), the covering one or else the one with the smallest gap
/// taken. A Gmsh tet10 liner's bore line had three nodes on the line by chance, at z = 0, 255
/// and 260 mm: the pistons' slices were spread between the ends and the peaks came out 50-60 %
/// low, exit 0. The detail gives the largest distance of a chosen node from the line and the
/// largest gap; a widened line with a gap still wider than [`LINE_GAP`] h is warned of. A line
/// as found that no widening improves (a structured deck coarse along the axis, whose line
/// has a node at each of its rows) is kept without a word.
fn widen_line(
    mesh: &mut Mesh,
    out: &mut [FoundSet],
    name: &str,
    on: &dyn Fn(usize, &[f64; 3]) -> bool,
    sign: f64,
    h: f64,
) {
    let Some(f) = out
        .iter_mut()
        .find(|f| f.name == name && f.source == "geometry")
    else {
        return;
    };
    let span = surface_span(mesh, on, sign);
    let exact = mesh.node_sets.get(name).cloned().unwrap_or_default();
    let mut best = (exact, f64::INFINITY, 0.0);
    best.1 = line_gap(mesh, &best.0, span);
    if best.0.len() >= 3 && best.1 <= LINE_GAP * h {
        return;
    }
    for w in [0.5 * h, h, 2.0 * h] {
        let line = nearest_on_line(mesh, on, sign, w, h);
        let gap = line_gap(mesh, &line, span);
        let covers_more = line.len() >= 3 && (best.0.len() < 3 || gap < best.1);
        if covers_more || (best.0.len() < 3 && line.len() > best.0.len()) {
            best = (line, gap, w);
        }
        if best.0.len() >= 3 && best.1 <= LINE_GAP * h {
            break;
        }
    }
    let (line, gap, w) = best;
    if w == 0.0 {
        // nothing covered better than the line as found
        return;
    }
    let off = line
        .iter()
        .map(|&n| mesh.nodes[n][0].abs())
        .fold(0.0, f64::max);
    f.nodes = line.len();
    f.detail += &format!(" (widened: nodes up to {off:.6} m off the line, gaps up to {gap:.6} m)");
    if line.len() >= 3 && gap > LINE_GAP * h {
        crate::text::warn(format!(
            "liner: the line '{name}' has no node within {} mm of the thrust line's plane for {} mm of its length (nodes up to {} mm off it taken): the slices' forces there are spread over that gap; refine the deck there or name the set",
            crate::text::num(2e3 * h),
            crate::text::num(gap * 1e3),
            crate::text::num(off * 1e3)
        ));
    }
    mesh.node_sets.insert(name.into(), line);
}

/// A thrust line covers its surface when no gap along z is wider than this many median
/// element edges h (a structured deck's line has a node at every element layer; a line of
/// stray nodes has gaps of the liner's length).
const LINE_GAP: f64 = 4.0;

/// The z-range of the surface `on` on the side sign y > 0 \[m\].
fn surface_span(mesh: &Mesh, on: &dyn Fn(usize, &[f64; 3]) -> bool, sign: f64) -> [f64; 2] {
    (0..mesh.nodes.len())
        .filter(|&n| on(n, &mesh.nodes[n]) && sign * mesh.nodes[n][1] > 0.0)
        .map(|n| mesh.nodes[n][2])
        .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], z| {
            [lo.min(z), hi.max(z)]
        })
}

/// The widest gap along z between the nodes `line`, and between the ends of `span` and
/// them \[m\] (infinite for no node).
fn line_gap(mesh: &Mesh, line: &[usize], span: [f64; 2]) -> f64 {
    let mut z: Vec<f64> = line.iter().map(|&n| mesh.nodes[n][2]).collect();
    if z.is_empty() {
        return f64::INFINITY;
    }
    z.sort_by(f64::total_cmp);
    let ends = (z[0] - span[0]).max(span[1] - z[z.len() - 1]);
    z.windows(2).map(|p| p[1] - p[0]).fold(ends, f64::max)
}

/// The nodes `on` the surface within `w` of the line x = 0, sign y > 0, at each height (levels
/// 0.25 h apart) the one nearest to it, bottom to top.
fn nearest_on_line(
    mesh: &Mesh,
    on: &dyn Fn(usize, &[f64; 3]) -> bool,
    sign: f64,
    w: f64,
    h: f64,
) -> Vec<usize> {
    let mut cand: Vec<usize> = (0..mesh.nodes.len())
        .filter(|&n| {
            let p = mesh.nodes[n];
            on(n, &p) && p[0].abs() < w && sign * p[1] > 0.0
        })
        .collect();
    cand.sort_by(|&a, &b| mesh.nodes[a][2].total_cmp(&mesh.nodes[b][2]));
    let mut line: Vec<usize> = Vec::new();
    for n in cand {
        match line.last_mut() {
            Some(last) if (mesh.nodes[n][2] - mesh.nodes[*last][2]).abs() < 0.25 * h => {
                if mesh.nodes[n][0].abs() < mesh.nodes[*last][0].abs() {
                    *last = n;
                }
            }
            _ => line.push(n),
        }
    }
    line
}

/// Adds node set `name` of the nodes satisfying `pred` unless the mesh names it.
fn add_set(
    mesh: &mut Mesh,
    part: &str,
    name: &str,
    pred: &dyn Fn(usize, &[f64; 3]) -> bool,
    detail: String,
) -> FoundSet {
    if let Some(v) = mesh.node_sets.get(name) {
        return found(part, name, "deck", v.len(), String::new());
    }
    let nodes: Vec<usize> = (0..mesh.nodes.len())
        .filter(|&n| pred(n, &mesh.nodes[n]))
        .collect();
    let count = nodes.len();
    mesh.node_sets.insert(name.into(), nodes);
    found(part, name, "geometry", count, detail)
}

/// Adds the single-node set `name`: the node nearest `target` among those satisfying `pred`.
fn add_point(
    mesh: &mut Mesh,
    part: &str,
    name: &str,
    target: [f64; 3],
    pred: &dyn Fn(usize, &[f64; 3]) -> bool,
) -> FoundSet {
    if let Some(v) = mesh.node_sets.get(name) {
        return found(part, name, "deck", v.len(), String::new());
    }
    let best = (0..mesh.nodes.len())
        .filter(|&n| pred(n, &mesh.nodes[n]))
        .map(|n| (dist(&mesh.nodes[n], &target), n))
        .min_by(|a, b| a.0.total_cmp(&b.0));
    match best {
        Some((d, n)) => {
            let p = mesh.nodes[n];
            mesh.node_sets.insert(name.into(), vec![n]);
            let detail = format!(
                "node at ({:.6}, {:.6}, {:.6}) m, {:.3e} m from ({:.6}, {:.6}, {:.6})",
                p[0], p[1], p[2], d, target[0], target[1], target[2]
            );
            found(part, name, "geometry", 1, detail)
        }
        None => {
            mesh.node_sets.insert(name.into(), Vec::new());
            found(part, name, "geometry", 0, "no candidate node".into())
        }
    }
}

fn found(part: &str, name: &str, source: &str, nodes: usize, detail: String) -> FoundSet {
    FoundSet {
        part: part.into(),
        name: name.into(),
        source: source.into(),
        nodes,
        detail,
    }
}

/// Radius of `p` about the bore axis at x = `xc`, y = 0.
fn radius_about(p: &[f64; 3], xc: f64) -> f64 {
    (p[0] - xc).hypot(p[1])
}

/// The counterbore floor of the bore at `xc`: the highest node in the annulus under the flange.
fn counterbore_z(cm: &Mesh, xc: f64, s: &LinerShape, tol: f64) -> Option<f64> {
    let z = cm
        .nodes
        .iter()
        .filter(|p| {
            let r = radius_about(p, xc);
            r > s.outer_radius - tol && r < s.flange_radius - tol
        })
        .map(|p| p[2])
        .fold(f64::NEG_INFINITY, f64::max);
    z.is_finite().then_some(z)
}

/// Moves the crankcase along z so that cylinder 1's counterbore floor meets the liner's flange
/// underside; returns the shift \[m\].
pub fn seat_crankcase(cm: &mut Mesh, axis_x: &[f64], s: &LinerShape) -> Result<f64, FindError> {
    let tol = 0.02 * mesh_size(cm);
    let x1 = axis_x.first().copied().unwrap_or(0.0);
    let z = counterbore_z(cm, x1, s, tol).ok_or_else(|| {
        fail(
            "crankcase",
            format!(
                "no counterbore under the liner flange of cylinder 1 (no node at radius {:.6}..{:.6} m around x = {x1:.6} m, y = 0): the crankcase must be in the engine frame (bore axes at x_c = (c - (N+1)/2) pitch, y = 0, z up), or name the sets seat_<c>",
                s.outer_radius, s.flange_radius
            ),
        )
    })?;
    let shift = s.seat_z - z;
    if shift.abs() > 1e-12 * s.length {
        for p in &mut cm.nodes {
            p[2] += shift;
        }
    }
    Ok(shift)
}

/// Moves a seated crankcase across (x, y) so that its bores' axes meet the engine frame's:
/// by minus the mean offset of the bores' centres, each the least-squares circle (Kasa fit)
/// through the crankcase's nodes on its guide band ([`guide_band`], r_o - tol <= r <= r_p +
/// tol). A deck off the frame by less than its mesh tolerance tol (its origin's roundoff, a
/// rounded pitch) then seats each flange's rim ring whole: 10 um off in x left the rim's nodes
/// on one side of every seat out (r > r_f + 7 um) and moved the frequencies by 1.8e-3, exit 0.
/// An offset beyond tol is left to the fit checks, which refuse it naming the node; one below
/// 1e-12 of the liner's length is not applied. Returns the shift \[m\].
pub fn centre_crankcase(cm: &mut Mesh, axis_x: &[f64], s: &LinerShape) -> [f64; 2] {
    let tol = 0.02 * mesh_size(cm);
    let offsets: Vec<[f64; 2]> = axis_x
        .iter()
        .filter_map(|&xc| {
            let ([g0, g1], _) = guide_band(cm, xc, s)?;
            let ring: Vec<[f64; 2]> = cm
                .nodes
                .iter()
                .filter(|p| p[2] > g0 - tol && p[2] < g1 + tol)
                .filter(|p| s.holds(radius_about(p, xc), tol))
                .map(|p| [p[0] - xc, p[1]])
                .collect();
            circle_fit(&ring).map(|(c, _)| c)
        })
        .collect();
    if offsets.is_empty() {
        return [0.0; 2];
    }
    let n = offsets.len() as f64;
    let d = [0, 1].map(|a| offsets.iter().map(|o| o[a]).sum::<f64>() / n);
    let size = d[0].hypot(d[1]);
    if !(size > 1e-12 * s.length && size < tol) {
        return [0.0; 2];
    }
    for p in &mut cm.nodes {
        p[0] -= d[0];
        p[1] -= d[1];
    }
    [-d[0], -d[1]]
}

/// The guide band [z0, z1] of the bore at `xc`: the lowest of its `bore_bands` below the
/// seat (module docs). Also returns how far the bore's faces reach below the liner's bottom
/// \[m\] (<= 0: none).
pub fn guide_band(cm: &Mesh, xc: f64, s: &LinerShape) -> Option<([f64; 2], f64)> {
    let tol = 0.02 * mesh_size(cm);
    let (bands, below) = bore_bands(cm, xc, s, tol);
    let below_seat: Vec<[f64; 2]> = bands
        .iter()
        .copied()
        .filter(|b| b[1] < s.seat_z - tol)
        .collect();
    below_seat
        .first()
        .or(bands.first())
        .map(|&band| (band, below))
}

/// The z-bands [z0, z1], bottom to top, where the crankcase's bore at `xc` holds the liner:
/// element faces with at least three corners in r_o <= r <= r_p ([`LinerShape::holds`])
/// between the liner's bottom and its seat, merged where they meet, cut at the liner's bottom
/// z = 0. Also returns how far those faces reach below the liner's bottom \[m\] (<= 0: none).
fn bore_bands(cm: &Mesh, xc: f64, s: &LinerShape, tol: f64) -> (Vec<[f64; 2]>, f64) {
    let mut below = f64::NEG_INFINITY;
    let on = |p: &[f64; 3]| s.holds(radius_about(p, xc), tol);
    let spans = face_spans(cm, on)
        // faces along the liner, between its bottom and its seat; a face reaching below
        // the liner's bottom (a crankcase seated lower, its guide bore longer than the
        // liner) counts from the bottom up: dropped, the band above it was taken for the
        // guide and the liner hung from its deck bore (the small engine's slap +30-39 %)
        .filter(|&[lo, hi]| hi > tol && hi > lo + tol && hi < s.seat_z + tol)
        .map(|[lo, hi]| {
            below = below.max(-lo);
            [lo.max(0.0), hi]
        })
        .collect();
    (merge_spans(spans, tol), below)
}

/// The top z of the crankcase's set `guide_<k>` (-inf without one).
fn guide_top(cm: &Mesh, k: usize) -> f64 {
    let guide = cm.node_set(&format!("guide_{k}")).unwrap_or(&[]);
    guide
        .iter()
        .map(|&n| cm.nodes[n][2])
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The underside of the deck plate's bore at cylinder `k`'s axis x = `xc` (liner frame): the
/// lowest z of the `bore_bands` band that meets the seat, when it lies above the guide set's
/// top. From there up the deck holds the liner and no coolant wets it. None: the bore has no
/// such band (the liner is held only at its flange and guide).
pub fn deck_underside(cm: &Mesh, (k, xc): (usize, f64), s: &LinerShape, tol: f64) -> Option<f64> {
    let (bands, _) = bore_bands(cm, xc, s, tol);
    let top = guide_top(cm, k);
    bands
        .last()
        .filter(|b| b[1] >= s.seat_z - tol && b[0] > top)
        .map(|b| b[0])
}

/// Keeps of the liner's wet surface (`coolant_wetted`) the nodes at most `deck` high (within
/// the liner's tolerance), updating its count and detail in `found` when it was found or
/// generated there (a set named in the liner's deck is the user's: kept as named).
pub fn trim_wet_zone(liner: &mut Mesh, s: &LinerShape, deck: f64, found: &mut [FoundSet]) {
    let name = super::liner::COOLANT_WETTED;
    let entry = found
        .iter_mut()
        .find(|f| f.name == name && f.part == "liner");
    if entry.as_ref().is_some_and(|f| f.source == "deck") {
        return;
    }
    let nodes = &liner.nodes;
    let Some(set) = liner.node_sets.get_mut(name) else {
        return;
    };
    set.retain(|&n| nodes[n][2] < deck + s.tol);
    let z = set.iter().map(|&n| nodes[n][2]);
    let lo = z.clone().fold(f64::INFINITY, f64::min);
    let hi = z.fold(f64::NEG_INFINITY, f64::max);
    if let Some(f) = entry {
        f.nodes = set.len();
        f.detail = format!(
            "the outer wall, z {lo:.6}..{hi:.6} m: from the guide band's top to the deck plate's underside at z {deck:.6} m (the deck bore holds the liner above it)"
        );
    }
}

/// Checks that cylinder `k`'s analysis heights (`analysis_z`, liner frame) lie in its coolant
/// zone: above its guide set's top and below the underside of the deck plate's bore (the
/// lowest z of the [`bore_bands`] band that meets the seat, when the bore at `xc` has one).
/// The scene's checks use its own `crankcase.deck_thickness_mm` and guide keys, which a
/// crankcase deck does not follow: a deck plate 40 mm thicker put point 1 inside the plate, a
/// wall no coolant wets (its response reported as if it were, exit 0).
fn check_coolant_zone(
    cm: &Mesh,
    (k, xc): (usize, f64),
    s: &LinerShape,
    analysis_z: &[f64],
    tol: f64,
) -> Result<(), FindError> {
    let guide_top = guide_top(cm, k);
    let deck = deck_underside(cm, (k, xc), s, tol).unwrap_or(f64::INFINITY);
    let mm = |z: f64| crate::text::num((s.length - z) * 1e3);
    for (j, &z) in analysis_z.iter().enumerate() {
        let place = if z > deck - tol {
            format!("inside the crankcase's deck plate, which holds the liner from {} mm below its top up", mm(deck))
        } else if z < guide_top + tol {
            format!("in the crankcase's guide band, which holds the liner from {} mm below its top down", mm(guide_top))
        } else {
            continue;
        };
        return Err(fail(
            "crankcase",
            format!(
                "cylinder {k}: analysis point {} ({} mm below the liner top: liner.analysis_first_depth_mm, liner.analysis_spacing_mm) lies {place}: the points must lie in the coolant zone, {}..{} mm below the liner top for this deck",
                j + 1,
                mm(z),
                if deck.is_finite() { mm(deck) } else { mm(s.seat_z) },
                mm(guide_top)
            ),
        ));
    }
    Ok(())
}

/// Bores of a seated crankcase beyond the scene's cylinders (`axis_x`, at least two, their
/// spacing the pitch): at x_1 - pitch and x_N + pitch, a hole of the liner's outer radius (no
/// node within r_o - tol of the axis between the liner's bottom and its seat) ringed by the
/// crankcase (a node on r = r_o there). Returns their axes \[m\]. A deck of a longer engine
/// set under the scene's two axes ran with its third bore empty, exit 0 (points 3-10 % off).
pub fn extra_bores(cm: &Mesh, axis_x: &[f64], s: &LinerShape) -> Vec<f64> {
    let [first, second, ..] = axis_x else {
        return Vec::new();
    };
    let pitch = second - first;
    let last = axis_x[axis_x.len() - 1];
    let tol = 0.02 * mesh_size(cm);
    let along = |p: &&[f64; 3]| p[2] > tol && p[2] < s.seat_z - tol;
    [first - pitch, last + pitch]
        .into_iter()
        .filter(|&xc| {
            let (hole, wall) = cm
                .nodes
                .iter()
                .filter(along)
                .map(|p| radius_about(p, xc))
                .fold((true, false), |(hole, wall), r| {
                    (hole && r >= s.outer_radius - tol, wall || s.holds(r, tol))
                });
            hole && wall
        })
        .collect()
}

/// The crankcase's interface and point inputs.
pub struct CrankcaseTargets<'a> {
    pub axis_x: &'a [f64],
    /// Heights of the analysis points in the liner frame \[m\].
    pub analysis_z: &'a [f64],
}

/// Adds to a seated crankcase the sets it does not name: per bore `seat_c`, `guide_c`,
/// `point_c_k`, and `deck_top`; returns what each set is and where it came from.
pub fn crankcase_sets(
    cm: &mut Mesh,
    s: &LinerShape,
    t: &CrankcaseTargets<'_>,
) -> Result<Vec<FoundSet>, FindError> {
    let tol = 0.02 * mesh_size(cm);
    let mut out = Vec::new();
    for (c, &xc) in t.axis_x.iter().enumerate() {
        let k = c + 1;
        let (ro, rf, zs) = (s.outer_radius, s.flange_radius, s.seat_z);
        // under the flange only: a node of the floor a mesh tolerance beyond its rim (the
        // bridge between close counterbores, pitch 149 mm against a 148 mm flange) is not
        // seated, and the engine's fit check (1e-4 of the pitch) refused the set found. The
        // floor's plane keeps the mesh tolerance: a node off it is found and then refused by
        // that check, naming it, rather than left out of the seat without a word.
        let rim = rf + tol.min(1e-4 * rf);
        let seat = move |_, p: &[f64; 3]| (p[2] - zs).abs() < tol && radius_about(p, xc) <= rim;
        let found_seat = add_set(
            cm,
            "crankcase",
            &format!("seat_{k}"),
            &seat,
            format!("z = {zs:.6} m, r <= {rf:.6} m"),
        );
        if found_seat.source == "geometry" {
            check_seat_ring(cm, (k, xc), s, tol)?;
        }
        out.push(found_seat);
        let name = format!("guide_{k}");
        if let Some(v) = cm.node_sets.get(&name) {
            out.push(found("crankcase", &name, "deck", v.len(), String::new()));
        } else {
            let ([g0, g1], below) = guide_band(cm, xc, s).ok_or_else(|| {
                let nearest = cm
                    .nodes
                    .iter()
                    .filter(|p| p[2] > tol && p[2] < zs - tol)
                    .map(|p| radius_about(p, xc))
                    .fold(f64::INFINITY, f64::min);
                fail("crankcase", format!("cylinder {k}: no bore surface holding the liner (r {} to {} mm, its wet wall to its pilot) below the seat (the liner's guide band) around x = {} mm, y = 0; the crankcase's nearest node there is at r = {} mm: a bore with a radial clearance is not coupled (give it the liner's pilot diameter), or the deck is not in the engine frame (a shift or a tilt of the bore axes); or name the set {name}", crate::text::num(ro * 1e3), crate::text::num(s.pilot_radius * 1e3), crate::text::num(xc * 1e3), crate::text::num(nearest * 1e3)))
            })?;
            if below > tol {
                crate::text::warn(format!(
                    "crankcase: cylinder {k}'s guide bore reaches {} mm below the liner's bottom once the crankcase is seated on the liner's flange: coupled over z {}..{} mm only; check that the two decks' flange heights and liner lengths agree",
                    crate::text::num(below * 1e3),
                    crate::text::num(g0 * 1e3),
                    crate::text::num(g1 * 1e3)
                ));
            }
            let guide = move |_, p: &[f64; 3]| {
                s.holds(radius_about(p, xc), tol) && p[2] > g0 - tol && p[2] < g1 + tol
            };
            out.push(add_set(
                cm,
                "crankcase",
                &name,
                &guide,
                format!("r {ro:.6}..{:.6} m, z {g0:.6}..{g1:.6} m", s.pilot_radius),
            ));
        }
        check_coolant_zone(cm, (k, xc), s, t.analysis_z, tol)?;
        for (j, &z) in t.analysis_z.iter().enumerate() {
            let name = format!("point_{k}_{}", j + 1);
            // across the coolant: beyond the pilot, whose bores' corners are nearer
            let beyond = move |_, p: &[f64; 3]| p[1] > s.pilot_radius + tol;
            out.push(add_point(cm, "crankcase", &name, [xc, ro, z], &beyond));
        }
    }
    let zs = s.seat_z;
    out.push(add_set(
        cm,
        "crankcase",
        "deck_top",
        &|_, p| (p[2] - zs).abs() < tol,
        format!("z = {zs:.6} m"),
    ));
    Ok(out)
}

/// Refuses a seat found under only the rim of cylinder `k`'s flange: its nodes' smallest
/// radius r_in about the bore axis beyond the middle of the flange's bearing ring,
/// r_in > (r_p + r_f) / 2. That is a counterbore narrower than the flange: the highest
/// crankcase node under the flange is then the deck top around the counterbore, so the liner
/// was seated on the deck top a counterbore depth too high (exit 0 before). A chamfer at the
/// bore's mouth takes far less than half the ring. The message gives the floor below (the
/// highest node inside r_in, below the seat), when there is one.
fn check_seat_ring(
    cm: &Mesh,
    (k, xc): (usize, f64),
    s: &LinerShape,
    tol: f64,
) -> Result<(), FindError> {
    let Some(seat) = cm.node_sets.get(&format!("seat_{k}")) else {
        return Ok(());
    };
    let r_in = seat
        .iter()
        .map(|&n| radius_about(&cm.nodes[n], xc))
        .fold(f64::INFINITY, f64::min);
    if !(r_in.is_finite() && r_in > 0.5 * (s.pilot_radius + s.flange_radius)) {
        return Ok(());
    }
    let floor = cm
        .nodes
        .iter()
        .filter(|p| p[2] < s.seat_z - tol && radius_about(p, xc) < r_in - tol)
        .filter(|p| radius_about(p, xc) > s.outer_radius - tol)
        .map(|p| p[2])
        .fold(f64::NEG_INFINITY, f64::max);
    let mm = |v: f64| crate::text::num(v * 1e3);
    let below = if floor.is_finite() {
        format!(
            "; the counterbore's floor is {} mm lower",
            mm(s.seat_z - floor)
        )
    } else {
        String::new()
    };
    Err(fail(
        "crankcase",
        format!(
            "cylinder {k}: the liner's flange (radius {} mm) would rest only on its rim, at r {}..{} mm (the deck top around the counterbore): the crankcase's counterbore is narrower than the flange{below}; check the two decks' flange and counterbore diameters, or name the set seat_{k}",
            mm(s.flange_radius),
            mm(r_in),
            mm(s.flange_radius)
        ),
    ))
}

/// A scene's box set: the nodes inside [x0, x1] x [y0, y1] x [z0, z1] \[m\].
pub fn box_set(mesh: &mut Mesh, part: &str, name: &str, b: &[f64; 6]) -> FoundSet {
    let inside = |p: &[f64; 3]| (0..3).all(|a| p[a] >= b[a] && p[a] <= b[a + 3]);
    let nodes: Vec<usize> = (0..mesh.nodes.len())
        .filter(|&n| inside(&mesh.nodes[n]))
        .collect();
    let count = nodes.len();
    mesh.node_sets.insert(name.into(), nodes);
    let detail = format!(
        "box ({:.6}, {:.6}, {:.6})..({:.6}, {:.6}, {:.6}) m",
        b[0], b[1], b[2], b[3], b[4], b[5]
    );
    found(part, name, "box", count, detail)
}

/// Guide band of a crankcase that names its `guide_1` set: the set's z-range.
pub fn named_guide_band(cm: &Mesh) -> Option<[f64; 2]> {
    let g = cm.node_set("guide_1")?;
    let z = g.iter().map(|&n| cm.nodes[n][2]);
    let lo = z.clone().fold(f64::INFINITY, f64::min);
    let hi = z.fold(f64::NEG_INFINITY, f64::max);
    (lo.is_finite() && hi >= lo).then_some([lo, hi])
}
