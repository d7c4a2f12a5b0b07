//! Participating media (002; Mitsuba 3's `homogeneous` and `heterogeneous`): extinction σ_t,
//! scattering σ_s = α σ_t, absorption σ_a = σ_t − σ_s per RGB channel, a phase function, and
//! emitted radiance L_e emitted per unit length as σ_a L_e (NOTES-002 §0, an ircache extension).
//!
//! - [`phase`]: isotropic and Henyey–Greenstein.
//! - [`volume`]: constants and voxel grids.
//! - [`tracking`]: free-flight sampling (delta tracking with spectral weights) and transmittance
//!   (closed form, ratio tracking) along rays that pass through `null` boundaries.

pub mod majorant;
pub mod phase;
pub mod tracking;
pub mod volume;

use ircache_math::{Rgb, Vec3};
use ircache_scene::{MediumDesc, MediumKind};
pub use phase::Phase;
pub use volume::Volume;

/// A medium ready for lookups.
#[derive(Clone, Debug)]
pub struct Medium {
    /// Extinction before `scale`.
    sigma_t: Volume,
    /// Single-scattering albedo.
    albedo: Volume,
    /// Emitted radiance, if any.
    emission: Option<Volume>,
    /// Applied to `sigma_t`.
    scale: f32,
    /// The phase function.
    pub phase: Phase,
    /// Next-event estimation at scattering events.
    pub sample_emitters: bool,
    /// Largest extinction over space and channels (the delta-tracking majorant).
    pub majorant: f32,
    /// Where a heterogeneous medium exists (its `sigma_t` volume's box), world space.
    pub bounds: Option<(Vec3, Vec3)>,
    /// σ_t is the same everywhere inside (closed-form transmittance).
    pub homogeneous: bool,
    /// Local majorants of a grid's extinction.
    pub majorants: Option<majorant::MajorantGrid>,
}

/// The coefficients at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coefficients {
    /// Extinction.
    pub sigma_t: Rgb,
    /// Scattering.
    pub sigma_s: Rgb,
    /// Emitted radiance (black without emission).
    pub emission: Rgb,
}

/// The gradients of [`Coefficients`] in space, per channel (r, g, b).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoefficientGradients {
    /// ∇σ_t.
    pub sigma_t: [Vec3; 3],
    /// ∇σ_s.
    pub sigma_s: [Vec3; 3],
    /// ∇ of the emitted radiance.
    pub emission: [Vec3; 3],
}

impl CoefficientGradients {
    /// ∇σ_a = ∇σ_t − ∇σ_s (where σ_a > 0; the clamp of [`Coefficients::sigma_a`] has no
    /// gradient below).
    #[must_use]
    pub fn sigma_a(&self, c: &Coefficients) -> [Vec3; 3] {
        let a = c.sigma_t - c.sigma_s;
        let positive = [a.r > 0.0, a.g > 0.0, a.b > 0.0];
        [0, 1, 2].map(|k| {
            if positive[k] {
                self.sigma_t[k] - self.sigma_s[k]
            } else {
                Vec3::ZERO
            }
        })
    }
}

impl Coefficients {
    /// Absorption σ_t − σ_s.
    #[inline]
    #[must_use]
    pub fn sigma_a(&self) -> Rgb {
        (self.sigma_t - self.sigma_s).max(Rgb::ZERO)
    }
}

impl Medium {
    /// From the description.
    #[must_use]
    pub fn from_desc(desc: &MediumDesc) -> Medium {
        let sigma_t = Volume::from_desc(&desc.sigma_t);
        let majorant = desc.scale * sigma_t.max().max_channel();
        let bounds = match desc.kind {
            MediumKind::Homogeneous => None,
            MediumKind::Heterogeneous => {
                let to_world = match &desc.sigma_t {
                    ircache_scene::VolumeDesc::Constant { to_world, .. } => *to_world,
                    ircache_scene::VolumeDesc::Grid(g) => g.to_world,
                };
                let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
                for c in 0..8u32 {
                    let p = Vec3::new((c & 1) as f32, ((c >> 1) & 1) as f32, ((c >> 2) & 1) as f32);
                    let w = to_world.transform_point3(p);
                    lo = lo.min(w);
                    hi = hi.max(w);
                }
                Some((lo, hi))
            }
        };
        let majorants = match &sigma_t {
            Volume::Grid(g) => Some(majorant::MajorantGrid::new(g, desc.scale, g.to_unit())),
            Volume::Constant(_) => None,
        };
        Medium {
            majorants,
            homogeneous: sigma_t.is_constant(),
            sigma_t,
            albedo: Volume::from_desc(&desc.albedo),
            emission: desc.emission.as_ref().map(Volume::from_desc),
            scale: desc.scale,
            phase: Phase::from_desc(&desc.phase),
            sample_emitters: desc.sample_emitters,
            majorant,
            bounds,
        }
    }

    /// The coefficients at world point `p` (inside the medium).
    #[inline]
    #[must_use]
    pub fn at(&self, p: Vec3) -> Coefficients {
        let sigma_t = self.sigma_t.eval(p) * self.scale;
        Coefficients {
            sigma_t,
            sigma_s: sigma_t * self.albedo.eval(p),
            emission: self.emission.as_ref().map_or(Rgb::ZERO, |e| e.eval(p)),
        }
    }

    /// [`Self::at`] and the coefficients' gradients per channel (r, g, b), exact for the
    /// volumes' interpolants: ∇σ_t = scale ∇v, ∇σ_s = ∇σ_t a + σ_t ∇a (a the albedo).
    #[inline]
    #[must_use]
    pub fn at_with_gradient(&self, p: Vec3) -> (Coefficients, CoefficientGradients) {
        let (v, gv) = self.sigma_t.eval_with_gradient(p);
        let (albedo, ga) = self.albedo.eval_with_gradient(p);
        let (emission, ge) = self
            .emission
            .as_ref()
            .map_or((Rgb::ZERO, [Vec3::ZERO; 3]), |e| e.eval_with_gradient(p));
        let sigma_t = v * self.scale;
        let (st, al) = (
            [sigma_t.r, sigma_t.g, sigma_t.b],
            [albedo.r, albedo.g, albedo.b],
        );
        let gt = gv.map(|g| g * self.scale);
        let gs = [0, 1, 2].map(|c| gt[c] * al[c] + ga[c] * st[c]);
        (
            Coefficients {
                sigma_t,
                sigma_s: sigma_t * albedo,
                emission,
            },
            CoefficientGradients {
                sigma_t: gt,
                sigma_s: gs,
                emission: ge,
            },
        )
    }

    /// True for a point inside the medium's box (everywhere for a medium without one).
    #[inline]
    #[must_use]
    pub fn contains(&self, p: Vec3) -> bool {
        self.bounds
            .is_none_or(|(lo, hi)| p.cmpge(lo).all() && p.cmple(hi).all())
    }

    /// The coefficients where they are the same everywhere inside (constant extinction and
    /// albedo): the densities of free-flight sampling are then closed forms.
    #[must_use]
    pub fn constant_coefficients(&self) -> Option<Coefficients> {
        (self.sigma_t.is_constant() && self.albedo.is_constant()).then(|| self.at(Vec3::ZERO))
    }

    /// Calls `f(t0, t1, majorant)` for the pieces of `[t0, t1]` along `o + t d` with a bound on
    /// the extinction in each (local majorants in grids, the medium's majorant elsewhere), in
    /// order, until `f` returns false.
    #[inline]
    pub fn for_each_segment(
        &self,
        o: Vec3,
        d: Vec3,
        t0: f32,
        t1: f32,
        mut f: impl FnMut(f32, f32, f32) -> bool,
    ) {
        match &self.majorants {
            Some(grid) => grid.for_each_segment(o, d, t0, t1, f),
            None => {
                f(t0, t1, self.majorant);
            }
        }
    }

    /// Where along `o + t d`, from `t0`, the optical depth of the medium's majorants (local ones
    /// in grids) reaches `depth`; `None` where it does not before `t1`.
    #[must_use]
    pub fn majorant_depth_reached(
        &self,
        o: Vec3,
        d: Vec3,
        t0: f32,
        t1: f32,
        depth: f64,
    ) -> Option<f64> {
        let (mut sum, mut reached) = (0.0f64, None);
        self.for_each_segment(o, d, t0, t1, |a, b, majorant| {
            let (a, b, majorant) = (f64::from(a), f64::from(b), f64::from(majorant));
            if sum + majorant * (b - a) >= depth {
                reached = Some(a + (depth - sum) / majorant);
                return false;
            }
            sum += majorant * (b - a);
            true
        });
        reached
    }

    /// The normal (an axis) of the face of the medium's box nearest `p`, where a ray crossing
    /// the box there enters or leaves it; zero for a medium without a box.
    #[must_use]
    pub fn box_face_normal(&self, p: Vec3) -> Vec3 {
        let Some((lo, hi)) = self.bounds else {
            return Vec3::ZERO;
        };
        let (a, b) = ((p - lo).abs(), (p - hi).abs());
        let axis = (0..3)
            .min_by(|&i, &j| a[i].min(b[i]).total_cmp(&a[j].min(b[j])))
            .unwrap_or(0);
        let mut n = Vec3::ZERO;
        n[axis] = 1.0;
        n
    }

    /// True when the medium emits.
    #[must_use]
    pub fn emits(&self) -> bool {
        self.emission
            .as_ref()
            .is_some_and(|e| e.max().max_channel() > 0.0)
    }

    /// The part `[t0, t1]` of `[0, t_max]` along `o + t d` inside the medium (its box for a
    /// heterogeneous medium); `None` when empty.
    #[inline]
    #[must_use]
    pub fn clip(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<(f32, f32)> {
        let Some((lo, hi)) = self.bounds else {
            return (t_max > 0.0).then_some((0.0, t_max));
        };
        let (mut t0, mut t1) = (0.0f32, t_max);
        for a in 0..3 {
            let inv = 1.0 / d[a];
            let (mut near, mut far) = ((lo[a] - o[a]) * inv, (hi[a] - o[a]) * inv);
            if near > far {
                std::mem::swap(&mut near, &mut far);
            }
            // NaN (d = 0 on the slab's plane) leaves the interval as it is.
            if near > t0 {
                t0 = near;
            }
            if far < t1 {
                t1 = far;
            }
        }
        (t0 < t1).then_some((t0, t1))
    }
}
