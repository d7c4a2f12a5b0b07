//! Pixels that nothing moving reaches, and the running mean of their sampled light over an
//! animation's frames (`ircache animate --accumulate`).
//!
//! An `ic` pixel sample's radiance is the part the cache gave (the records' irradiance and
//! glossy light at the frame's own records, the photon maps) plus the part the path sampled:
//! emission, direct light, the lobes traced ([`crate::integrators::ic::IcIntegrator::li_parts`]).
//! The temporal cache keeps the first smooth over time (001 ch. 5); the second is the pixel
//! noise, which a per-frame render draws afresh each frame. Where nothing that moved between
//! two frames can reach a pixel's sampled light, that light is the same random variable in
//! both, so the pixel keeps the mean of it over the frames since it last changed, draws each
//! later frame's samples as the next of one sequence for the run ([`crate::render::render_runs`]:
//! stratified over the run, where frames of seeds of their own were not, and slivers of a bright
//! lamp at the edge of a pixel stayed noisy) and adds the frame's cached part: the still parts
//! of a view converge over the sequence as a progressive renderer's do, and what moves is
//! rendered as before.
//!
//! Which pixels are still, conservatively, between frames `from` and `to`:
//! - nothing at all where the camera moved, where a moving shape emits, where shapes move in a
//!   scene lit by an environment, in participating media, or through a thin lens;
//! - else a pixel is still where its footprint (a 3 × 3 grid of camera rays over the pixel
//!   widened by the filter's radius) hits only static, opaque surfaces whose BSDF is Lambertian
//!   alone (the path ends there: its light samples and emission are all it traced), or misses,
//!   and no moving shape's box, at either frame, meets the hull of the camera and the hits (what
//!   the camera rays cross), nor the hull of the hits and any light's box or direction (what
//!   the shadow rays and the rays that find the light cross). The hits' box is widened by a
//!   quarter of its size for the parts of the footprint between the grid's rays.
//!
//! The hull of two boxes A and B is ∪ₜ (1 − t)A + tB over t ∈ [0, 1], each a box whose faces
//! move linearly with t, so whether a third box meets it is a question of intervals in t.

use crate::camera::Projection;
use crate::scene::Scene;
use ircache_image::Image;
use ircache_math::{Ray, Rgb, Vec2, Vec3};
use ircache_scene::animation::{Animation, Target};
use ircache_scene::{EmitterDesc, Geometry, SceneDesc};
use rayon::prelude::*;

/// An axis-aligned box (`lower > upper` on an axis: empty).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub lower: Vec3,
    /// Upper corner.
    pub upper: Vec3,
}

impl Aabb {
    /// The empty box.
    pub const EMPTY: Aabb = Aabb {
        lower: Vec3::splat(f32::INFINITY),
        upper: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The box holding `p` alone.
    #[must_use]
    pub fn point(p: Vec3) -> Aabb {
        Aabb { lower: p, upper: p }
    }

    /// This box grown to hold `p`.
    #[must_use]
    pub fn with(self, p: Vec3) -> Aabb {
        Aabb {
            lower: self.lower.min(p),
            upper: self.upper.max(p),
        }
    }

    /// True when it holds no point.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.lower.cmpgt(self.upper).any()
    }

    /// This box widened by `d` on every side.
    #[must_use]
    pub fn widened(self, d: f32) -> Aabb {
        Aabb {
            lower: self.lower - Vec3::splat(d),
            upper: self.upper + Vec3::splat(d),
        }
    }

    /// This box moved by `v`.
    #[must_use]
    pub fn moved(self, v: Vec3) -> Aabb {
        Aabb {
            lower: self.lower + v,
            upper: self.upper + v,
        }
    }
}

/// Whether box `c` meets the convex hull of boxes `a` and `b` (∪ₜ (1 − t)a + tb, module doc).
#[must_use]
pub fn hull_meets(a: &Aabb, b: &Aabb, c: &Aabb) -> bool {
    if a.is_empty() || b.is_empty() || c.is_empty() {
        return false;
    }
    // Each face gives lower(t) ≤ c.upper and upper(t) ≥ c.lower, linear in t: keep the t
    // where all hold.
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    let mut keep = |at0: f32, at1: f32, bound: f32, below: bool| {
        // f(t) = at0 + t (at1 − at0), wanted f ≤ bound (below) or f ≥ bound.
        let (f0, slope) = if below {
            (at0 - bound, at1 - at0)
        } else {
            (bound - at0, at0 - at1)
        };
        // f0 + t·slope ≤ 0.
        if slope == 0.0 {
            if f0 > 0.0 {
                t1 = -1.0;
            }
        } else if slope > 0.0 {
            t1 = t1.min(-f0 / slope);
        } else {
            t0 = t0.max(-f0 / slope);
        }
    };
    for i in 0..3 {
        keep(a.lower[i], b.lower[i], c.upper[i], true);
        keep(a.upper[i], b.upper[i], c.lower[i], false);
    }
    t0 <= t1
}

/// Where a light's light comes from, for the hull of a pixel's hits and the light.
#[derive(Clone, Copy, Debug, PartialEq)]
enum LightReach {
    /// A light within this box (area lights' shapes, point and spot lights).
    Box(Aabb),
    /// A distant light arriving along this direction of travel.
    Distant(Vec3),
}

/// What moved between two frames, as the pixel test needs it.
#[derive(Clone, Debug, Default)]
pub struct Change {
    /// Nothing is still (the camera or a light moved, or the scene is one the test leaves
    /// alone: module doc).
    pub everything: bool,
    /// Per shape (as [`SceneDesc::shapes`]), whether it moved.
    pub moved: Vec<bool>,
    /// The moving shapes' boxes at both frames.
    pub boxes: Vec<Aabb>,
    /// The lights, static where anything is still.
    lights: Vec<LightReach>,
}

impl Change {
    /// What moved in `animation` of the scene `base` between frames `from` and `to`.
    #[must_use]
    pub fn between(animation: &Animation, base: &SceneDesc, from: f32, to: f32) -> Change {
        let mut change = Change {
            moved: vec![false; base.shapes.len()],
            ..Change::default()
        };
        for track in &animation.tracks {
            let (a, b) = (track.motion(from), track.motion(to));
            if a == b {
                continue;
            }
            match track.target {
                Target::Camera => change.everything = true,
                Target::Shape(i) => {
                    let shape = &base.shapes[i];
                    change.everything |= shape.emitter.is_some();
                    change.moved[i] = true;
                    for m in [a, b] {
                        change.boxes.push(geometry_bounds(&shape.geometry, &m));
                    }
                }
            }
        }
        let moving = !change.boxes.is_empty();
        change.everything |= moving && !base.media.is_empty();
        change.everything |= moving
            && matches!(base.sensor.projection, Projection::ThinLens { aperture_radius, .. } if aperture_radius > 0.0);
        for (i, shape) in base.shapes.iter().enumerate() {
            if shape.emitter.is_some() && !change.moved[i] {
                let bounds = geometry_bounds(&shape.geometry, &ircache_math::Mat4::IDENTITY);
                change.lights.push(LightReach::Box(bounds));
            }
        }
        for emitter in &base.emitters {
            match emitter {
                EmitterDesc::Point { position, .. } => {
                    change.lights.push(LightReach::Box(Aabb::point(*position)));
                }
                EmitterDesc::Spot { to_world, .. } => {
                    let p = to_world.transform_point3(Vec3::ZERO);
                    change.lights.push(LightReach::Box(Aabb::point(p)));
                }
                EmitterDesc::Directional { direction, .. } => {
                    change
                        .lights
                        .push(LightReach::Distant(direction.normalize()));
                }
                EmitterDesc::Constant { .. } | EmitterDesc::Envmap { .. } => {
                    change.everything |= moving;
                }
            }
        }
        change
    }

    /// True when nothing moved.
    #[must_use]
    pub fn is_none(&self) -> bool {
        !self.everything && self.boxes.is_empty()
    }
}

/// The box of `geometry` moved by `m`.
fn geometry_bounds(geometry: &Geometry, m: &ircache_math::Mat4) -> Aabb {
    match geometry {
        Geometry::Mesh(mesh) => mesh
            .positions
            .iter()
            .fold(Aabb::EMPTY, |b, p| b.with(m.transform_point3(*p))),
        Geometry::Sphere { center, radius, .. } => {
            let r = radius * m.transform_vector3(Vec3::X).length();
            Aabb::point(m.transform_point3(*center)).widened(r)
        }
    }
}

/// Per pixel of a `width` × `height` image (row by row) of `scene` as it is at the later frame,
/// whether its sampled light is the same as at the earlier one of `change` (module doc); the
/// samples' offsets reach `filter_radius` pixels from the pixel's centre.
#[must_use]
pub fn still_pixels(
    scene: &Scene,
    change: &Change,
    (width, height): (usize, usize),
    filter_radius: f32,
) -> Vec<bool> {
    if change.everything {
        return vec![false; width * height];
    }
    if change.boxes.is_empty() {
        return vec![true; width * height];
    }
    // Past every surface: where the camera rays that miss are followed to.
    let far = 4.0 * scene.radius;
    let inv = Vec2::new(1.0 / width as f32, 1.0 / height as f32);
    let offsets = [-filter_radius, 0.0, filter_radius];
    let pixel = |x: usize, y: usize| -> bool {
        let (mut origins, mut seen, mut hits) = (Aabb::EMPTY, Aabb::EMPTY, Aabb::EMPTY);
        for dy in offsets {
            for dx in offsets {
                let film = (Vec2::new(x as f32 + 0.5 + dx, y as f32 + 0.5 + dy)) * inv;
                let ray: Ray = scene.camera.generate_ray(film);
                origins = origins.with(ray.o);
                let Some(hit) = scene.accel.intersect(&ray) else {
                    seen = seen.with(ray.o + ray.d * far);
                    continue;
                };
                let Some(shape) = scene.shapes.get(hit.geom_id as usize) else {
                    return false;
                };
                if change.moved.get(hit.geom_id as usize) != Some(&false)
                    || shape.null
                    || shape.masked
                    || shape.thin_sheet
                    || shape.media.interior.is_some()
                    || shape.media.exterior.is_some()
                {
                    return false;
                }
                let it = scene.interaction(&ray, &hit);
                let bsdf = it.bsdf(&scene.materials[shape.material], ray.d);
                if bsdf.has_glossy() || bsdf.has_delta() {
                    return false;
                }
                seen = seen.with(it.p);
                hits = hits.with(it.p);
            }
        }
        if !hits.is_empty() {
            let size = (hits.upper - hits.lower).length();
            hits = hits.widened(0.25 * size + 1e-5 * scene.radius);
            seen = seen.with(hits.lower).with(hits.upper);
        }
        let meets = |a: &Aabb, b: &Aabb| change.boxes.iter().any(|c| hull_meets(a, b, c));
        if meets(&origins, &seen) {
            return false;
        }
        !change.lights.iter().any(|light| match *light {
            LightReach::Box(l) => meets(&hits, &l),
            LightReach::Distant(d) => meets(&hits, &hits.moved(-d * far)),
        })
    };
    (0..width * height)
        .into_par_iter()
        .map(|i| pixel(i % width, i / width))
        .collect()
}

/// The still runs of an animation's pixels: the frames over which each pixel's sampled light
/// stays the same random variable, and the mean of it over each run.
///
/// Frames are added in order ([`Self::add`]); each pixel's current run ends where the next
/// frame is not still for it. A frame's image is then its cached part plus, per pixel, the mean
/// over the run holding it: while rendering, the run so far ([`Self::so_far`]); once the
/// sequence is done, the whole run ([`Self::whole`]), so a pixel still over the whole sequence
/// has every frame's samples in every frame.
#[derive(Clone, Debug, Default)]
pub struct StillRuns {
    /// Per pixel, the current run (frames 0 before the first frame).
    open: Vec<Run>,
    /// Per pixel, its ended runs of two frames or more, in order: first and last frame, mean.
    /// (A run of one frame is that frame's own sampled light.)
    ended: Vec<Vec<(u32, u32, Rgb)>>,
}

/// A pixel's current run.
#[derive(Clone, Copy, Debug, Default)]
struct Run {
    /// Its first frame.
    first: u32,
    /// The sum of its frames' sampled light, each weighted by its samples.
    sum: Rgb,
    /// Its samples.
    samples: u32,
    /// Its frames.
    frames: u32,
}

impl Run {
    fn mean(&self) -> Rgb {
        self.sum / self.samples.max(1) as f32
    }
}

impl StillRuns {
    /// No frames yet, for `pixels` pixels.
    #[must_use]
    pub fn new(pixels: usize) -> StillRuns {
        StillRuns {
            open: vec![Run::default(); pixels],
            ended: vec![Vec::new(); pixels],
        }
    }

    /// The samples each pixel's run has drawn before the next frame, where the frame is `still`
    /// for it, else 0 (a run begins): where the pixel's samples in that frame begin in its
    /// run's sequence ([`crate::render::render_runs`]).
    #[must_use]
    pub fn drawn(&self, still: &[bool]) -> Vec<u32> {
        self.open
            .iter()
            .zip(still)
            .map(|(run, &s)| if s { run.samples } else { 0 })
            .collect()
    }

    /// Adds frame `frame` (the one after the last added), rendered from [`Self::drawn`]: its
    /// sampled light (its `image` less the `cached` part), the mean of each pixel's `samples`,
    /// continues each pixel's run where the frame is `still` for it and begins a new run
    /// elsewhere. A run's mean weighs its frames by their samples (adaptive sampling gives
    /// frames different counts).
    pub fn add(
        &mut self,
        frame: u32,
        still: &[bool],
        (image, cached): (&Image, &Image),
        samples: &[u32],
    ) {
        for (i, (open, ended)) in self.open.iter_mut().zip(&mut self.ended).enumerate() {
            let n = samples[i];
            let l = (image.pixels[i] - cached.pixels[i]) * n as f32;
            if still[i] && open.frames > 0 {
                open.sum += l;
                open.samples += n;
                open.frames += 1;
            } else {
                if open.frames > 1 {
                    ended.push((open.first, frame - 1, open.mean()));
                }
                *open = Run {
                    first: frame,
                    sum: l,
                    samples: n,
                    frames: 1,
                };
            }
        }
    }

    /// True when some pixel has a run of two frames or more (else every frame is its own).
    #[must_use]
    pub fn any_kept(&self) -> bool {
        self.open.iter().any(|o| o.frames > 1) || self.ended.iter().any(|e| !e.is_empty())
    }

    /// The last added frame's image while the sequence goes on: its `cached` part plus each
    /// pixel's mean over its run so far (a run of one frame: the frame's own `image`).
    #[must_use]
    pub fn so_far(&self, (image, cached): (&Image, &Image)) -> Image {
        let mut out = image.clone();
        for ((o, c), run) in out.pixels.iter_mut().zip(&cached.pixels).zip(&self.open) {
            if run.frames > 1 {
                *o = *c + run.mean();
            }
        }
        out
    }

    /// Frame `frame`'s image once the sequence has ended (at the last frame added): its
    /// `cached` part plus each pixel's mean over the whole run holding the frame (a run of one
    /// frame: the frame's own `image`).
    #[must_use]
    pub fn whole(&self, frame: u32, (image, cached): (&Image, &Image)) -> Image {
        let mut out = image.clone();
        for (i, o) in out.pixels.iter_mut().enumerate() {
            let run = &self.open[i];
            let ended = &self.ended[i];
            let k = ended.partition_point(|&(_, last, _)| last < frame);
            let mean = if run.frames > 1 && frame >= run.first {
                Some(run.mean())
            } else {
                ended.get(k).filter(|r| r.0 <= frame).map(|r| r.2)
            };
            if let Some(mean) = mean {
                *o = cached.pixels[i] + mean;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ircache_math::Rng;

    fn aabb(l: [f32; 3], u: [f32; 3]) -> Aabb {
        Aabb {
            lower: Vec3::from(l),
            upper: Vec3::from(u),
        }
    }

    /// The hull test against points of the hull drawn at random: a box that holds one of them
    /// meets the hull; the test says no only where none of many does, and agrees with boxes
    /// placed by hand.
    #[test]
    fn the_hull_of_two_boxes() {
        let a = aabb([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]);
        let b = aabb([4.0, 0.0, 0.0], [5.0, 1.0, 1.0]);
        // Between them, above them, beside the far one, across the middle thinly.
        assert!(hull_meets(&a, &b, &aabb([2.0, 0.4, 0.4], [2.1, 0.6, 0.6])));
        assert!(!hull_meets(&a, &b, &aabb([2.0, 1.1, 0.4], [2.1, 1.3, 0.6])));
        assert!(!hull_meets(&a, &b, &aabb([5.5, 0.0, 0.0], [6.0, 1.0, 1.0])));
        assert!(hull_meets(&a, &b, &aabb([2.5, -1.0, 0.5], [2.5, 2.0, 0.5])));
        // A point light: the hull is a pyramid; its apex side narrows.
        let p = Aabb::point(Vec3::new(4.0, 0.5, 0.5));
        assert!(!hull_meets(&a, &p, &aabb([3.5, 0.0, 0.0], [3.6, 0.3, 0.3])));
        assert!(hull_meets(&a, &p, &aabb([3.5, 0.4, 0.4], [3.6, 0.6, 0.6])));

        let mut rng = Rng::new(7, 0);
        let mut u = || rng.next_f32();
        for _ in 0..2000 {
            let corner = |u: &mut dyn FnMut() -> f32, s: f32| {
                let l = Vec3::new(u(), u(), u()) * 4.0 - 2.0;
                Aabb {
                    lower: l,
                    upper: l + Vec3::new(u(), u(), u()) * s,
                }
            };
            let (a, b, c) = (
                corner(&mut u, 1.0),
                corner(&mut u, 1.0),
                corner(&mut u, 0.5),
            );
            // Points of the hull: (1 − t) p + t q.
            let mut inside = false;
            for _ in 0..400 {
                let t = u();
                let p = a.lower + (a.upper - a.lower) * Vec3::new(u(), u(), u());
                let q = b.lower + (b.upper - b.lower) * Vec3::new(u(), u(), u());
                let x = p + (q - p) * t;
                inside |= x.cmpge(c.lower).all() && x.cmple(c.upper).all();
            }
            if inside {
                assert!(hull_meets(&a, &b, &c), "{a:?} {b:?} {c:?}");
            }
        }
    }

    /// Runs: a pixel still over every frame has every frame's samples in each; one that
    /// changes takes its runs apart; frames weigh by their samples; the image so far is the run
    /// so far; the cached part is the frame's own.
    #[test]
    fn still_runs() {
        let image = |a: f32, b: f32| {
            let mut i = Image::new(2, 1);
            i.set(0, 0, Rgb::splat(a));
            i.set(1, 0, Rgb::splat(b));
            i
        };
        let pair = |i: &Image| (i.get(0, 0).r, i.get(1, 0).r);
        let mut runs = StillRuns::new(2);
        assert_eq!(runs.drawn(&[true, true]), vec![0, 0]);
        assert!(!runs.any_kept());
        // Pixel 0 still throughout; pixel 1 changes at frames 2 and 3. Sampled light 2, 4, 6,
        // 8 and 10, 20, 30, 40 over a cached part of 1.
        let images = [
            image(3.0, 11.0),
            image(5.0, 21.0),
            image(7.0, 31.0),
            image(9.0, 41.0),
        ];
        let still = [[false, false], [true, true], [true, false], [true, false]];
        let cached = image(1.0, 1.0);
        let mut so_far = Vec::new();
        for (f, (im, st)) in images.iter().zip(&still).enumerate() {
            assert_eq!(
                runs.drawn(st),
                vec![4 * f as u32 * u32::from(st[0]), [0, 4, 0, 0][f]]
            );
            runs.add(f as u32, st, (im, &cached), &[4, [4, 12, 4, 4][f]]);
            so_far.push(pair(&runs.so_far((im, &cached))));
        }
        assert_eq!(
            so_far,
            vec![(3.0, 11.0), (4.0, 18.5), (5.0, 31.0), (6.0, 41.0)]
        );
        assert!(runs.any_kept());
        let whole: Vec<_> = (0..4)
            .map(|f| pair(&runs.whole(f, (&images[f as usize], &cached))))
            .collect();
        // Pixel 0: 1 + mean(2, 4, 6, 8) = 6 in every frame; pixel 1: frames 0–1 one run, its
        // frames weighed by their samples (4 and 12: 1 + 17.5), then runs of one frame.
        assert_eq!(
            whole,
            vec![(6.0, 18.5), (6.0, 18.5), (6.0, 31.0), (6.0, 41.0)]
        );
    }
}
