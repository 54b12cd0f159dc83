//! Piston skirt: slices, hot profile and the penalty contact law.
//!
//! The skirt (length L_s, its top h_top above the pin) is cut into n slices of equal height;
//! slice i sits at h_i above the pin (negative below). In the thrust plane its radius is
//!
//!   R_s(h) = R_b - c/2 - b ((h - h_max) / L_b)^2 + R_b alpha_p (T_p(h) - T_ref),
//!
//! c the cold diametral clearance, b the barrel drop at the farther skirt end (L_b its distance
//! from the widest height h_max), T_p linear from the skirt top to its bottom. The bore grows
//! to R_b (1 + alpha_l (T_l - T_ref)); the hot radial gap of a centred piston is
//! g_i = R_b,hot - R_s(h_i).
//!
//! Contact law of one slice (thrust side; the anti-thrust side mirrors it): with p the radial
//! penetration at the thrust line (p = y + h_i phi - g_i - u_liner), the skirt's surface at
//! angle psi from the thrust line penetrates by p cos psi - o(psi), where
//!   o(psi) = g_i (1 - cos psi) + (w / 2) sin^2 psi
//! (conforming radii, ovality w = major minus minor diameter, major axis on the thrust axis).
//! Sampling psi at 0, +-15, +-30, +-45 deg with weights normalised so that a fully conforming
//! skirt gives the slice stiffness k:
//!   F(p) = k / sum_j cos^2 psi_j * sum_j cos psi_j max(0, p cos psi_j - o_j)  (+ c_d dp/dt if p > 0).
//! F is convex, piecewise linear in p: exact Newton pieces.

/// Sample angles of the contact arc \[deg\].
pub const PSI_DEG: [f64; 7] = [-45.0, -30.0, -15.0, 0.0, 15.0, 30.0, 45.0];

/// Piecewise-linear elastic contact law of one slice: F(p) = sum_j k_j max(0, c_j p - o_j) c_j.
#[derive(Clone, Debug, PartialEq)]
pub struct SliceLaw {
    /// k_j = k w_j with the normalised weights [N/m].
    k: [f64; 7],
    c: [f64; 7],
    o: [f64; 7],
}

/// A linear piece F = a + k_t p of a law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Piece {
    pub a: f64,
    pub kt: f64,
    /// Bit j set when sample j is in contact.
    pub mask: u8,
}

impl SliceLaw {
    /// Law of a slice with hot radial gap `gap` \[m\], ovality `ovality` \[m\], stiffness `k` [N/m].
    pub fn new(k: f64, gap: f64, ovality: f64) -> Self {
        let rad = std::f64::consts::PI / 180.0;
        let c = PSI_DEG.map(|d| (d * rad).cos());
        let s2 = PSI_DEG.map(|d| (d * rad).sin().powi(2));
        let norm: f64 = c.iter().map(|x| x * x).sum();
        let mut o = [0.0; 7];
        for j in 0..7 {
            o[j] = gap * (1.0 - c[j]) + 0.5 * ovality * s2[j];
        }
        Self {
            k: [k / norm; 7],
            c,
            o,
        }
    }

    /// The linear piece that holds at penetration `p`.
    pub fn piece(&self, p: f64) -> Piece {
        let mut out = Piece {
            a: 0.0,
            kt: 0.0,
            mask: 0,
        };
        for j in 0..7 {
            if self.c[j] * p - self.o[j] > 0.0 {
                out.kt += self.k[j] * self.c[j] * self.c[j];
                out.a -= self.k[j] * self.c[j] * self.o[j];
                out.mask |= 1 << j;
            }
        }
        out
    }

    /// Onset of contact: the largest p at which no sample touches, min_j o_j / c_j over the
    /// samples with c_j > 0 (F(p) = 0 for every p <= onset; +inf when no sample can touch).
    pub fn onset(&self) -> f64 {
        (0..7)
            .filter(|&j| self.c[j] > 0.0)
            .map(|j| self.o[j] / self.c[j])
            .fold(f64::INFINITY, f64::min)
    }

    /// The linear piece with the samples of `mask` in contact.
    pub fn piece_of(&self, mask: u8) -> Piece {
        let mut out = Piece {
            a: 0.0,
            kt: 0.0,
            mask,
        };
        for j in 0..7 {
            if mask & (1 << j) != 0 {
                out.kt += self.k[j] * self.c[j] * self.c[j];
                out.a -= self.k[j] * self.c[j] * self.o[j];
            }
        }
        out
    }

    /// Elastic force F(p) \[N\].
    pub fn force(&self, p: f64) -> f64 {
        let pc = self.piece(p);
        pc.a + pc.kt * p
    }
}

/// Slices of the skirt with their hot gaps.
#[derive(Clone, Debug, PartialEq)]
pub struct Skirt {
    /// Height of each slice centre above the pin \[m\], top to bottom.
    pub heights: Vec<f64>,
    /// Hot radial gap of a centred piston at each slice \[m\] (negative: interference).
    pub gaps: Vec<f64>,
    pub laws: Vec<SliceLaw>,
}

pub use crate::scene::spec::SkirtSpec;

impl Skirt {
    /// Slices, hot gaps and contact laws of `s`.
    pub fn new(s: &SkirtSpec) -> Self {
        let rb = s.bore / 2.0;
        let n = s.slices;
        let dh = s.length / n as f64;
        let hmax = -s.barrel_max_below_pin;
        let bottom = s.top_above_pin - s.length;
        let lb = (s.top_above_pin - hmax).abs().max((hmax - bottom).abs());
        let rb_hot = rb * (1.0 + s.liner_expansion * (s.liner_temp_c - s.reference_temp_c));
        let mut heights = Vec::with_capacity(n);
        let mut gaps = Vec::with_capacity(n);
        for i in 0..n {
            let h = s.top_above_pin - (i as f64 + 0.5) * dh;
            let frac = (s.top_above_pin - h) / s.length;
            let t = s.skirt_top_temp_c + (s.skirt_bottom_temp_c - s.skirt_top_temp_c) * frac;
            let r = rb - s.clearance / 2.0 - s.barrel * ((h - hmax) / lb).powi(2)
                + rb * s.piston_expansion * (t - s.reference_temp_c);
            heights.push(h);
            gaps.push(rb_hot - r);
        }
        let laws = gaps
            .iter()
            .map(|&g| SliceLaw::new(s.stiffness, g, s.ovality))
            .collect();
        Self {
            heights,
            gaps,
            laws,
        }
    }

    /// Smallest hot diametral clearance (2 min g_i) \[m\].
    pub fn hot_clearance(&self) -> f64 {
        2.0 * self.gaps.iter().copied().fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conforming_slice_has_the_stated_stiffness_and_ovality_softens_it() {
        let law = SliceLaw::new(1e8, 0.0, 0.0);
        // all samples engage at once: F = k p exactly
        assert!((law.force(1e-5) - 1e3).abs() < 1e-9);
        assert_eq!(law.force(-1e-6), 0.0);
        // with a gap or ovality only the thrust line engages first: F = k w_0 p, w_0 = 1/sum c^2
        let oval = SliceLaw::new(1e8, 0.0, 40e-6);
        let w0 = 1.0
            / PSI_DEG
                .iter()
                .map(|d| d.to_radians().cos().powi(2))
                .sum::<f64>();
        assert!((oval.force(1e-7) - 1e8 * w0 * 1e-7).abs() < 1e-9);
        // convex: the tangent grows with p
        assert!(oval.piece(5e-5).kt > oval.piece(1e-6).kt);
        assert!(oval.force(1e-4) < law.force(1e-4));
    }

    #[test]
    fn hot_gap_follows_clearance_barrel_and_expansion() {
        let spec = SkirtSpec {
            bore: 0.115,
            length: 0.065,
            top_above_pin: 0.020,
            slices: 13,
            clearance: 80e-6,
            barrel: 0.0,
            barrel_max_below_pin: 0.0,
            ovality: 0.0,
            piston_expansion: 0.0,
            skirt_top_temp_c: 20.0,
            skirt_bottom_temp_c: 20.0,
            liner_expansion: 0.0,
            liner_temp_c: 20.0,
            reference_temp_c: 20.0,
            stiffness: 1e8,
        };
        let cold = Skirt::new(&spec);
        assert!(cold.gaps.iter().all(|g| (g - 40e-6).abs() < 1e-12));
        // uniform 100 K on piston (12e-6) and liner (11e-6): gap shrinks by R (1.2e-3 - 1.1e-3)
        let hot = Skirt::new(&SkirtSpec {
            piston_expansion: 12e-6,
            liner_expansion: 11e-6,
            skirt_top_temp_c: 120.0,
            skirt_bottom_temp_c: 120.0,
            liner_temp_c: 120.0,
            ..spec.clone()
        });
        let expect = 40e-6 - 0.0575 * (1.2e-3 - 1.1e-3);
        assert!(hot.gaps.iter().all(|g| (g - expect).abs() < 1e-12));
        // barrel: the middle slice (h = -12.5 mm) is the widest when h_max = -12.5 mm
        let barrel = Skirt::new(&SkirtSpec {
            barrel: 15e-6,
            barrel_max_below_pin: 0.0125,
            ..spec
        });
        assert!((barrel.gaps[6] - 40e-6).abs() < 1e-12);
        assert!(barrel.gaps[0] > 40e-6 && barrel.gaps[12] > 40e-6);
    }
}
