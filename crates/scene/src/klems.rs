//! Klems BSDF matrices, as WINDOW 6 and Radiance's `genBSDF`/`wrapBSDF` write them and
//! Radiance's `BSDF` material reads them (`src/common/bsdf_m.c`): plain data with the geometry
//! of the LBNL angle bases.
//!
//! An angle basis divides a hemisphere into rings of polar angle, each into equal azimuthal
//! patches centred on φ = 2πk/n (the first ring is the one patch around the pole). A matrix
//! holds one value of the BSDF (sr⁻¹) per pair of incident and outgoing patches.
//!
//! Sides are Radiance's: *front* is the side the surface normal points to (WINDOW's back: the
//! loader swaps them as `bsdf_m.c` does). Directions point away from the surface. A patch is
//! found in its basis after the direction is mapped into the basis's hemisphere (z ≥ 0) by the
//! component's [`HemisphereMap`]s, which are `bsdf_m.c`'s `fi`/`fo`/`bi`/`bo` index functions.

use ircache_math::{Rgb, Vec3};
use std::path::PathBuf;
use std::sync::Arc;

/// An LBNL angle basis: rings of polar angle split into azimuthal patches.
#[derive(Clone, Debug, PartialEq)]
pub struct AngleBasis {
    /// The name the files use (`LBNL/Klems Full`, …).
    pub name: String,
    /// Lower polar bound of each ring in degrees, then 90.
    pub theta: Vec<f64>,
    /// Patches in each ring.
    pub phis: Vec<u32>,
    /// Index of each ring's first patch, then the number of patches.
    first: Vec<u32>,
    /// `cos θ` of each bound in `theta`.
    cos_theta: Vec<f32>,
}

impl AngleBasis {
    /// A basis from its rings' lower bounds (degrees, starting at 0) and patch counts; the last
    /// ring ends at 90°. `None` unless the bounds increase from 0 to below 90, the first ring is
    /// one patch and every other ring has at least one.
    #[must_use]
    pub fn new(name: &str, lower: &[f64], phis: &[u32]) -> Option<AngleBasis> {
        let increasing = lower.windows(2).all(|w| w[0] < w[1]);
        if lower.len() != phis.len()
            || lower.first() != Some(&0.0)
            || !increasing
            || *lower.last()? >= 90.0
            || phis.first() != Some(&1)
            || phis.contains(&0)
        {
            return None;
        }
        let theta: Vec<f64> = lower.iter().copied().chain([90.0]).collect();
        let mut first = vec![0u32];
        for &n in phis {
            first.push(first.last()?.checked_add(n)?);
        }
        Some(AngleBasis {
            name: name.into(),
            cos_theta: theta.iter().map(|t| t.to_radians().cos() as f32).collect(),
            theta,
            phis: phis.to_vec(),
            first,
        })
    }

    /// The bases `bsdf_m.c` knows by name (`LBNL/Klems Full`, `Half`, `Quarter`).
    #[must_use]
    pub fn standard(name: &str) -> Option<AngleBasis> {
        let (lower, phis): (&[f64], &[u32]) = match name.to_ascii_lowercase().as_str() {
            "lbnl/klems full" => (
                &[0.0, 5.0, 15.0, 25.0, 35.0, 45.0, 55.0, 65.0, 75.0],
                &[1, 8, 16, 20, 24, 24, 24, 16, 12],
            ),
            "lbnl/klems half" => (
                &[0.0, 6.5, 19.5, 32.5, 45.5, 58.5, 71.5],
                &[1, 8, 12, 16, 20, 12, 8],
            ),
            "lbnl/klems quarter" => (&[0.0, 9.0, 27.0, 45.0, 63.0], &[1, 8, 12, 12, 8]),
            _ => return None,
        };
        AngleBasis::new(name, lower, phis)
    }

    /// Number of patches.
    #[must_use]
    pub fn len(&self) -> usize {
        *self.first.last().unwrap_or(&0) as usize
    }

    /// True for a basis without patches (never built by [`AngleBasis::new`]).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The patch holding the unit direction `v` of the basis's hemisphere (`fo_getndx`): `None`
    /// for `v.z ≤ 0` (the horizon belongs to no patch).
    #[must_use]
    pub fn patch(&self, v: Vec3) -> Option<usize> {
        if v.z.is_nan() || v.z <= 0.0 {
            return None;
        }
        // The ring whose polar range holds v: cos θ falls from the pole outwards.
        let ring = self.cos_theta[1..].iter().position(|&c| v.z > c)?;
        let n = self.phis[ring];
        let mut azimuth = v.y.atan2(v.x);
        if azimuth < 0.0 {
            azimuth += std::f32::consts::TAU;
        }
        let mut k = (azimuth * (n as f32 / std::f32::consts::TAU) + 0.5) as u32;
        if k >= n {
            k = 0;
        }
        Some((self.first[ring] + k) as usize)
    }

    /// The ring of `patch` and its index in the ring.
    fn ring_of(&self, patch: usize) -> (usize, u32) {
        let ring = self.first[1..]
            .iter()
            .position(|&f| patch < f as usize)
            .unwrap_or(self.phis.len() - 1);
        (ring, patch as u32 - self.first[ring])
    }

    /// Projected solid angle of `patch`: π (cos²θ₀ − cos²θ₁) / n (`io_getohm`).
    #[must_use]
    pub fn projected_solid_angle(&self, patch: usize) -> f32 {
        let (ring, _) = self.ring_of(patch);
        let (c0, c1) = (self.cos_theta[ring], self.cos_theta[ring + 1]);
        std::f32::consts::PI * (c0 * c0 - c1 * c1) / self.phis[ring] as f32
    }

    /// A direction in `patch`, uniform in projected solid angle over it for `u` uniform in
    /// [0, 1)² (`fo_getvec`: cos²θ and φ linear in `u`).
    #[must_use]
    pub fn direction(&self, patch: usize, u: [f32; 2]) -> Vec3 {
        let (ring, k) = self.ring_of(patch);
        let (c0, c1) = (self.cos_theta[ring], self.cos_theta[ring + 1]);
        let cos2 = (1.0 - u[0]) * c0 * c0 + u[0] * c1 * c1;
        let cos = cos2.max(0.0).sqrt();
        let sin = (1.0 - cos2).max(0.0).sqrt();
        let azimuth = std::f32::consts::TAU * (k as f32 + u[1] - 0.5) / self.phis[ring] as f32;
        Vec3::new(azimuth.cos() * sin, azimuth.sin() * sin, cos)
    }
}

/// How a direction (local frame, away from the surface) maps into a basis's hemisphere:
/// `bsdf_m.c`'s index functions. Each map is its own inverse.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HemisphereMap {
    /// Incident from the front (`fi`): (−x, −y, z).
    FrontIncident,
    /// Leaving the front (`fo`): (x, y, z).
    FrontOutgoing,
    /// Incident from the back (`bi`): (−x, −y, −z).
    BackIncident,
    /// Leaving the back (`bo`): (x, y, −z).
    BackOutgoing,
}

impl HemisphereMap {
    /// `v` in the basis's hemisphere (and back: the map is an involution).
    #[inline]
    #[must_use]
    pub fn apply(self, v: Vec3) -> Vec3 {
        match self {
            HemisphereMap::FrontIncident => Vec3::new(-v.x, -v.y, v.z),
            HemisphereMap::FrontOutgoing => v,
            HemisphereMap::BackIncident => -v,
            HemisphereMap::BackOutgoing => Vec3::new(v.x, v.y, -v.z),
        }
    }
}

/// One scattering component: a matrix of BSDF values over incident × outgoing patches.
#[derive(Clone, Debug, PartialEq)]
pub struct KlemsMatrix {
    /// The basis of the incident directions (the file's column basis).
    pub incident: Arc<AngleBasis>,
    /// The basis of the outgoing directions (the file's row basis).
    pub outgoing: Arc<AngleBasis>,
    /// BSDF values (sr⁻¹, linear RGB), `values[o · incident.len() + i]` (`mBSDF_value`).
    pub values: Vec<Rgb>,
}

impl KlemsMatrix {
    /// The value for incident patch `i` and outgoing patch `o`.
    #[inline]
    #[must_use]
    pub fn value(&self, o: usize, i: usize) -> Rgb {
        self.values[o * self.incident.len() + i]
    }
}

/// Which component of a BSDF: reflection or transmission, and the side light arrives from
/// (Radiance's `rf`, `rb`, `tf`, `tb`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum KlemsComponent {
    /// Light arriving at the front, reflected to the front.
    ReflectFront,
    /// Light arriving at the back, reflected to the back.
    ReflectBack,
    /// Light arriving at the front, transmitted to the back.
    TransmitFront,
    /// Light arriving at the back, transmitted to the front.
    TransmitBack,
}

impl KlemsComponent {
    /// Every component.
    pub const ALL: [KlemsComponent; 4] = [
        KlemsComponent::ReflectFront,
        KlemsComponent::ReflectBack,
        KlemsComponent::TransmitFront,
        KlemsComponent::TransmitBack,
    ];

    /// The maps of the incident and the outgoing direction into their bases (`bsdf_m.c`'s
    /// `load_bsdf_data`).
    #[must_use]
    pub fn maps(self) -> (HemisphereMap, HemisphereMap) {
        use HemisphereMap as M;
        match self {
            KlemsComponent::ReflectFront => (M::FrontIncident, M::FrontOutgoing),
            KlemsComponent::ReflectBack => (M::BackIncident, M::BackOutgoing),
            KlemsComponent::TransmitFront => (M::FrontIncident, M::BackOutgoing),
            KlemsComponent::TransmitBack => (M::BackIncident, M::FrontOutgoing),
        }
    }
}

/// A Klems BSDF: up to four components (Radiance's sides), read from an XML file.
#[derive(Clone, PartialEq)]
pub struct KlemsBsdf {
    /// The file it was read from.
    pub source: PathBuf,
    /// The components, in the order of [`KlemsComponent::ALL`].
    pub components: [Option<KlemsMatrix>; 4],
}

/// The matrices' sizes and a digest of their bases and values (FNV-1a), not where the file
/// lies: scene hashes format it, and two copies of one file are the same BSDF.
impl std::fmt::Debug for KlemsBsdf {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut digest: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |bytes: &[u8]| {
            for b in bytes {
                digest = (digest ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3);
            }
        };
        let mut sizes = Vec::new();
        for m in &self.components {
            match m {
                Some(m) => {
                    sizes.push(format!("{}×{}", m.outgoing.len(), m.incident.len()));
                    for b in [&m.incident, &m.outgoing] {
                        for t in &b.theta {
                            eat(&t.to_le_bytes());
                        }
                        for n in &b.phis {
                            eat(&n.to_le_bytes());
                        }
                    }
                    for v in &m.values {
                        for c in [v.r, v.g, v.b] {
                            eat(&c.to_le_bytes());
                        }
                    }
                }
                None => {
                    sizes.push("none".into());
                    eat(b"none");
                }
            }
        }
        write!(
            f,
            "KlemsBsdf {{ components: {sizes:?}, digest: {digest:016x} }}"
        )
    }
}

impl KlemsBsdf {
    /// The matrix of component `c`, if the file has it.
    #[must_use]
    pub fn component(&self, c: KlemsComponent) -> Option<&KlemsMatrix> {
        self.components[c as usize].as_ref()
    }

    /// The component `bsdf.c`'s `SDevalBSDF` uses for an incident direction on the front or
    /// back and an outgoing one on the front or back; a missing transmission falls back to the
    /// other one (which the lookup then reads by reciprocity).
    #[must_use]
    pub fn component_for(
        &self,
        in_front: bool,
        out_front: bool,
    ) -> Option<(KlemsComponent, &KlemsMatrix)> {
        use KlemsComponent as C;
        let order: &[C] = match (in_front, out_front) {
            (true, true) => &[C::ReflectFront],
            (false, false) => &[C::ReflectBack],
            (true, false) => &[C::TransmitFront, C::TransmitBack],
            (false, true) => &[C::TransmitBack, C::TransmitFront],
        };
        order
            .iter()
            .find_map(|&c| self.component(c).map(|m| (c, m)))
    }
}

/// Where a direction pair falls in a component's matrix: `(o, i)` for `m.value(o, i)`, with
/// `bsdf_m.c`'s fallback to reciprocity (the two directions' roles swapped) when neither lies
/// on its side.
#[must_use]
pub fn matrix_entry(
    component: KlemsComponent,
    m: &KlemsMatrix,
    incident: Vec3,
    outgoing: Vec3,
) -> Option<(usize, usize)> {
    let (map_in, map_out) = component.maps();
    let i = m.incident.patch(map_in.apply(incident));
    let o = m.outgoing.patch(map_out.apply(outgoing));
    match (i, o) {
        (Some(i), Some(o)) => Some((o, i)),
        (None, None) => {
            let i = m.incident.patch(map_in.apply(outgoing))?;
            let o = m.outgoing.patch(map_out.apply(incident))?;
            Some((o, i))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_basis_has_145_patches_summing_to_pi() {
        for (name, n) in [
            ("LBNL/Klems Full", 145),
            ("LBNL/Klems Half", 77),
            ("LBNL/Klems Quarter", 41),
        ] {
            let b = AngleBasis::standard(name).unwrap();
            assert_eq!(b.len(), n, "{name}");
            let total: f32 = (0..n).map(|p| b.projected_solid_angle(p)).sum();
            assert!(
                (total - std::f32::consts::PI).abs() < 1e-5,
                "{name}: {total}"
            );
        }
    }

    #[test]
    fn a_patch_holds_the_directions_drawn_in_it() {
        let b = AngleBasis::standard("LBNL/Klems Full").unwrap();
        for p in 0..b.len() {
            for u in [[0.01, 0.02], [0.5, 0.5], [0.98, 0.97], [0.3, 0.9]] {
                let v = b.direction(p, u);
                assert!((v.length() - 1.0).abs() < 1e-5);
                assert_eq!(b.patch(v), Some(p), "patch {p} at {u:?}");
            }
        }
        // The pole and the first ring's patch centred on +x.
        assert_eq!(b.patch(Vec3::Z), Some(0));
        let t = 10f32.to_radians();
        assert_eq!(b.patch(Vec3::new(t.sin(), 0.0, t.cos())), Some(1));
        assert_eq!(b.patch(Vec3::new(t.sin(), -0.01, t.cos())), Some(1));
        assert_eq!(b.patch(Vec3::new(0.0, t.sin(), t.cos())), Some(3));
        assert_eq!(b.patch(Vec3::new(1.0, 0.0, 0.0)), None);
        assert_eq!(b.patch(Vec3::new(0.0, 0.0, -1.0)), None);
    }

    #[test]
    fn bad_bases_are_refused() {
        assert!(AngleBasis::new("x", &[0.0, 10.0], &[1, 8]).is_some());
        assert!(AngleBasis::new("x", &[0.0, 10.0], &[2, 8]).is_none());
        assert!(AngleBasis::new("x", &[0.0, 10.0, 5.0], &[1, 8, 8]).is_none());
        assert!(AngleBasis::new("x", &[0.0, 95.0], &[1, 8]).is_none());
        assert!(AngleBasis::new("x", &[0.0, 10.0], &[1, 0]).is_none());
    }
}
