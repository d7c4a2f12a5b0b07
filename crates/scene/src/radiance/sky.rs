//! The sky brightness functions of Radiance's sky generators, evaluated natively so that their
//! output renders without Radiance's function language:
//!
//! - gensky's `brightfunc skyfunc 2 skybr skybright.cal 0 3|7 type zenith ground [norm sx sy sz]`
//!   (`src/gen/skybright.cal`): CIE clear (type 1), overcast (2), uniform (3) and intermediate (4)
//!   skies;
//! - gendaylit's `brightfunc skyfunc 2 skybright perezlum.cal 0 10 diffuse ground c1..c5 sx sy sz`
//!   (`src/gen/perezlum.cal`): Perez et al.'s all-weather model.
//!
//! Both blend into the ground brightness below the horizon with weights `(D_z + 1.01)^±10`.
//! `D` is the direction looked in (world space; z up).

use super::parse::Primitive;
use ircache_math::DVec3;

/// A sky brightness function with its arguments.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SkyBrightness {
    /// `skybright.cal`.
    Cie {
        /// 1 clear, 2 overcast, 3 uniform, 4 intermediate.
        kind: u8,
        /// Zenith brightness.
        zenith: f64,
        /// Ground brightness.
        ground: f64,
        /// Normalisation by the sun's direction (clear and intermediate skies).
        norm: f64,
        /// Unit direction to the sun.
        sun: DVec3,
    },
    /// `perezlum.cal`.
    Perez {
        /// Diffuse normalisation.
        diffuse: f64,
        /// Ground brightness.
        ground: f64,
        /// The five Perez coefficients.
        c: [f64; 5],
        /// Unit direction to the sun.
        sun: DVec3,
    },
}

impl SkyBrightness {
    /// `None` when the primitive is not one of the two functions; otherwise the parsed function
    /// or what is wrong with its arguments.
    #[must_use]
    pub fn from_primitive(p: &Primitive) -> Option<Result<SkyBrightness, String>> {
        let file = |name: &str| {
            p.strings.get(1).is_some_and(|f| {
                std::path::Path::new(f).file_name().and_then(|n| n.to_str()) == Some(name)
            })
        };
        let r = &p.reals;
        if p.strings.len() >= 2 && p.strings[0] == "skybr" && file("skybright.cal") {
            if p.strings.len() > 2 {
                return Some(Err("transforms of skyfunc are not supported".into()));
            }
            let kind = r.first().copied().unwrap_or(0.0);
            return Some(match r.len() {
                3 | 7 if [1.0, 2.0, 3.0, 4.0].contains(&kind) => {
                    let sun = if r.len() == 7 {
                        DVec3::new(r[4], r[5], r[6]).normalize_or_zero()
                    } else {
                        DVec3::Z
                    };
                    let norm = if r.len() == 7 { r[3] } else { 1.0 };
                    if matches!(kind as u8, 1 | 4) && (r.len() != 7 || norm <= 0.0) {
                        Err(
                            "a clear or intermediate sky needs 7 arguments with a positive \
                             normalisation"
                                .into(),
                        )
                    } else {
                        Ok(SkyBrightness::Cie {
                            kind: kind as u8,
                            zenith: r[1],
                            ground: r[2],
                            norm,
                            sun,
                        })
                    }
                }
                _ => Err(format!(
                    "skybright.cal expects 3 or 7 real arguments starting with a sky type 1–4, \
                     found {} arguments",
                    r.len()
                )),
            });
        }
        if p.strings.len() >= 2 && p.strings[0] == "skybright" && file("perezlum.cal") {
            if p.strings.len() > 2 {
                return Some(Err("transforms of skyfunc are not supported".into()));
            }
            return Some(if r.len() == 10 {
                Ok(SkyBrightness::Perez {
                    diffuse: r[0],
                    ground: r[1],
                    c: [r[2], r[3], r[4], r[5], r[6]],
                    sun: DVec3::new(r[7], r[8], r[9]).normalize_or_zero(),
                })
            } else {
                Err(format!(
                    "perezlum.cal expects 10 real arguments, found {}",
                    r.len()
                ))
            });
        }
        None
    }

    /// The brightness factor looking in unit direction `d`.
    #[must_use]
    pub fn brightness(&self, d: DVec3) -> f64 {
        let dz = d.z;
        let up = (dz + 1.01).powi(10);
        let down = (dz + 1.01).powi(-10);
        let wmean = |x: f64, y: f64| (up * x + down * y) / (up + down);
        match *self {
            SkyBrightness::Cie {
                kind,
                zenith,
                ground,
                norm,
                sun,
            } => {
                let cosgamma = d.dot(sun).clamp(-1.0, 1.0);
                let gamma = cosgamma.acos();
                let zt = sun.z.clamp(-1.0, 1.0).acos();
                let eta = dz.clamp(-1.0, 1.0).acos();
                let sky = match kind {
                    1 => {
                        let horizon = if dz - 0.01 > 0.0 {
                            1.0 - (-0.32 / dz).exp()
                        } else {
                            1.0
                        };
                        zenith
                            * (0.91 + 10.0 * (-3.0 * gamma).exp() + 0.45 * cosgamma * cosgamma)
                            * horizon
                            / norm
                    }
                    2 => zenith * (1.0 + 2.0 * dz) / 3.0,
                    3 => zenith,
                    _ => {
                        zenith
                            * ((1.35 * (5.631 - 3.59 * eta).sin() + 3.12)
                                * (4.396 - 2.6 * zt).sin()
                                + 6.37
                                - eta)
                            / 2.326
                            * (gamma * -0.563 * ((2.629 - eta) * (1.562 - zt) + 0.812)).exp()
                            / norm
                    }
                };
                wmean(sky, ground)
            }
            SkyBrightness::Perez {
                diffuse,
                ground,
                c,
                sun,
            } => {
                let cosgamma = d.dot(sun).clamp(-1.0, 1.0);
                let gamma = cosgamma.acos();
                let z = if dz - 0.01 > 0.0 { dz } else { 0.01 };
                let sky = diffuse
                    * (1.0 + c[0] * (c[1] / z).exp())
                    * (1.0 + c[2] * (c[3] * gamma).exp() + c[4] * cosgamma * cosgamma);
                wmean(sky, ground)
            }
        }
    }
}
