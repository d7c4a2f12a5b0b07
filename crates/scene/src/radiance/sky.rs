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

/// Radiance's `gensky` (`src/gen/gensky.c`, `src/gen/sun.c`) carried out natively, so that a
/// scene's `!gensky` line loads without Radiance installed: the text gensky prints (its numbers
/// rounded as it prints them). `None` where it is not a gensky command or uses `-y` (Michalsky's
/// solar position), which then runs as a command; `Some(Err)` for arguments gensky refuses.
#[must_use]
pub fn gensky(words: &[String]) -> Option<Result<String, String>> {
    if words.first().map(String::as_str) != Some("gensky") || words.iter().any(|w| w == "-y") {
        return None;
    }
    Some(Gensky::parse(&words[1..]).map(|g| g.text()))
}

const DEG: f64 = std::f64::consts::PI / 180.0;
/// Radiance's `SKYEFFICACY` (D65's) and `SUNEFFICACY`, lm/W.
const SKY_EFFICACY: f64 = 203.0;
const SUN_EFFICACY: f64 = 208.0;
/// gensky's time zones and their standard meridians (degrees west).
const TIME_ZONES: [(&str, f64); 30] = [
    ("YST", 135.0),
    ("YDT", 120.0),
    ("PST", 120.0),
    ("PDT", 105.0),
    ("MST", 105.0),
    ("MDT", 90.0),
    ("CST", 90.0),
    ("CDT", 75.0),
    ("EST", 75.0),
    ("EDT", 60.0),
    ("AST", 60.0),
    ("ADT", 45.0),
    ("NST", 52.5),
    ("NDT", 37.5),
    ("GMT", 0.0),
    ("BST", -15.0),
    ("CET", -15.0),
    ("CEST", -30.0),
    ("EET", -30.0),
    ("EEST", -45.0),
    ("AST", -45.0),
    ("ADT", -60.0),
    ("GST", -60.0),
    ("GDT", -75.0),
    ("IST", -82.5),
    ("IDT", -97.5),
    ("JST", -135.0),
    ("NDT", -150.0),
    ("NZST", -180.0),
    ("NZDT", -195.0),
];

/// gensky's settings and what it computes from them.
struct Gensky {
    kind: u8,
    sun: bool,
    altitude: f64,
    azimuth: f64,
    zenith: f64,
    solar: f64,
    ground: f64,
    f2: f64,
}

impl Gensky {
    fn parse(args: &[String]) -> Result<Gensky, String> {
        let num = |i: usize| -> Result<f64, String> {
            let w = args.get(i).ok_or("gensky: too few arguments")?;
            w.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("gensky: expected a number, found \"{w}\""))
        };
        if args.len() < 3 {
            return Err("gensky: expected month day hour, or -ang altitude azimuth".into());
        }
        let (mut latitude, mut longitude, mut meridian) = (0.66, 2.13, 120.0 * DEG);
        let mut date: Option<(u32, u32, f64, bool)> = None;
        let (mut altitude, mut azimuth) = (0.0, 0.0);
        let mut got_meridian = false;
        if args[0] == "-ang" {
            altitude = num(1)? * DEG;
            azimuth = num(2)? * DEG;
        } else {
            let month = args[0].parse::<u32>().ok().filter(|m| (1..=12).contains(m));
            let day = args[1].parse::<u32>().ok().filter(|d| (1..=31).contains(d));
            let (Some(month), Some(day)) = (month, day) else {
                return Err(format!("gensky: bad date \"{} {}\"", args[0], args[1]));
            };
            let (hour, solar_time, zone) = parse_hour(&args[2])?;
            if let Some(m) = zone {
                meridian = m * DEG;
                got_meridian = true;
            }
            date = Some((month, day, hour, solar_time));
        }
        let (mut kind, mut sun) = (1u8, true);
        let (mut zenith, mut u_zenith, mut turbidity, mut reflectance) = (0.0, 0i8, 2.45, 0.2);
        let (mut solar, mut u_solar) = (0.0, 0i8);
        let mut i = 3;
        while i < args.len() {
            let a = args[i].as_str();
            let (sign, letter) = (a.chars().next(), a.chars().nth(1));
            if !matches!(sign, Some('-' | '+')) {
                return Err(format!("gensky: bad option \"{a}\""));
            }
            match letter {
                Some('s') => (kind, sun) = (1, sign == Some('+')),
                Some('i') => (kind, sun) = (4, sign == Some('+')),
                Some('c') => kind = 2,
                Some('u') => kind = 3,
                Some(c @ ('r' | 'R')) => {
                    u_solar = if c == 'R' { -1 } else { 1 };
                    solar = num(i + 1)?;
                    i += 1;
                }
                Some(c @ ('b' | 'B')) => {
                    u_zenith = if c == 'B' { -1 } else { 1 };
                    zenith = num(i + 1)?;
                    i += 1;
                }
                Some('t') => {
                    turbidity = num(i + 1)?;
                    i += 1;
                }
                Some('g') => {
                    reflectance = num(i + 1)?;
                    i += 1;
                }
                Some('a') => {
                    latitude = num(i + 1)? * DEG;
                    i += 1;
                }
                Some('o') => {
                    longitude = num(i + 1)? * DEG;
                    i += 1;
                }
                Some('m') => {
                    if !got_meridian {
                        meridian = num(i + 1)? * DEG;
                    }
                    i += 1;
                }
                _ => return Err(format!("gensky: unknown option \"{a}\"")),
            }
            i += 1;
        }
        let pi = std::f64::consts::PI;
        if let Some((month, day, hour, solar_time)) = date {
            // sun.c: Julian day, declination, solar time, altitude and azimuth.
            const DAYS: [u32; 12] = [0, 31, 59, 90, 120, 151, 181, 212, 243, 273, 304, 334];
            let jd = f64::from(DAYS[month as usize - 1] + day);
            let sd = 0.4093 * ((2.0 * pi / 365.0) * (jd - 81.0)).sin();
            let st = if solar_time {
                hour
            } else {
                hour + 0.170 * ((4.0 * pi / 373.0) * (jd - 80.0)).sin()
                    - 0.129 * ((2.0 * pi / 355.0) * (jd - 8.0)).sin()
                    + (12.0 / pi) * (meridian - longitude)
            };
            let h = st * (pi / 12.0);
            altitude = (latitude.sin() * sd.sin() - latitude.cos() * sd.cos() * h.cos()).asin();
            azimuth = -(sd.cos() * h.sin())
                .atan2(-latitude.cos() * sd.sin() - latitude.sin() * sd.cos() * h.cos());
        }
        let overcast = matches!(kind, 2 | 3);
        if !overcast && altitude > 87.0 * DEG {
            altitude = 87.0 * DEG;
        }
        let sz = altitude.sin();
        let normsc = || {
            let nf: [f64; 5] = if kind == 4 {
                [3.5556, -2.7152, -1.3081, 1.0660, 0.60227]
            } else {
                [2.766521, 0.547665, -0.369832, 0.009237, 0.059229]
            };
            let x = (altitude - pi / 4.0) / (pi / 4.0);
            nf.iter().rev().fold(0.0, |acc, c| acc * x + c)
        };
        let mut f2 = 0.0;
        let norm = match kind {
            3 => 1.0,
            2 => 0.777778,
            1 => {
                f2 = 0.274 * (0.91 + 10.0 * (-3.0 * (pi / 2.0 - altitude)).exp() + 0.45 * sz * sz);
                normsc() / f2 / pi
            }
            _ => {
                f2 = (2.739 + 0.9891 * (0.3119 + 2.6 * altitude).sin())
                    * (-(pi / 2.0 - altitude) * (0.4441 + 1.48 * altitude)).exp();
                normsc() / f2 / pi
            }
        };
        if u_zenith == -1 {
            zenith /= norm * pi;
        } else if u_zenith == 0 {
            zenith = if overcast {
                8.6 * sz + 0.123
            } else {
                (1.376 * turbidity - 1.81) * altitude.tan() + 0.38
            };
            if kind == 4 {
                zenith = (zenith + 8.6 * sz + 0.123) / 2.0;
            }
            zenith = if zenith < 0.0 {
                0.0
            } else {
                zenith * 1000.0 / SKY_EFFICACY
            };
        }
        let mut ground = zenith * norm;
        if !overcast && sz > 0.0 && (u_solar == 0 || solar > 0.0) {
            if u_solar == -1 {
                solar /= 5.98e-5 * sz;
            } else if u_solar == 0 {
                solar = 1.5e9 / SUN_EFFICACY * (1.147 - 0.147 / sz.max(0.16));
                if kind == 4 {
                    solar *= 0.15;
                }
            }
            ground += 6e-5 / pi * solar * sz;
        } else {
            sun = false;
        }
        ground *= reflectance;
        Ok(Gensky {
            kind,
            sun,
            altitude,
            azimuth,
            zenith,
            solar,
            ground,
            f2,
        })
    }

    /// What gensky prints (`printsky`), numbers rounded as it rounds them.
    fn text(&self) -> String {
        let e3 = |v: f64| format!("{v:.3e}");
        let dir = [
            -self.azimuth.sin() * self.altitude.cos(),
            -self.azimuth.cos() * self.altitude.cos(),
            self.altitude.sin(),
        ];
        let d = dir.map(|v| format!("{v:.6}")).join(" ");
        let mut t = String::new();
        if self.sun {
            let s = e3(self.solar);
            t.push_str(&format!(
                "void light solar\n0\n0\n3 {s} {s} {s}\n\nsolar source sun\n0\n0\n4 {d} 0.5\n\n"
            ));
        }
        t.push_str("void brightfunc skyfunc\n2 skybr skybright.cal\n0\n");
        if matches!(self.kind, 2 | 3) {
            t.push_str(&format!(
                "3 {} {} {}\n",
                self.kind,
                e3(self.zenith),
                e3(self.ground)
            ));
        } else {
            t.push_str(&format!(
                "7 {} {} {} {} {d}\n",
                self.kind,
                e3(self.zenith),
                e3(self.ground),
                e3(self.f2)
            ));
        }
        t
    }
}

/// gensky's `cvthour`: `[+]hh[.h|:mm][ZONE]`, `+` for solar time, a zone naming the standard
/// meridian (degrees west). Returns the hour, whether it is solar time, and the zone's meridian.
fn parse_hour(s: &str) -> Result<(f64, bool, Option<f64>), String> {
    let bad = || format!("gensky: bad time \"{s}\"");
    let (solar, rest) = match s.strip_prefix('+') {
        Some(r) => (true, r),
        None => (false, s),
    };
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == ':'))
        .unwrap_or(rest.len());
    let (time, zone) = rest.split_at(end);
    let hour = match time.split_once(':') {
        Some((h, m)) => {
            h.parse::<f64>().map_err(|_| bad())? + m.parse::<f64>().map_err(|_| bad())? / 60.0
        }
        None => time.parse::<f64>().map_err(|_| bad())?,
    };
    if zone.is_empty() {
        return Ok((hour, solar, None));
    }
    if solar {
        return Err(format!("gensky: a solar time \"{s}\" takes no time zone"));
    }
    let upper = zone.to_ascii_uppercase();
    TIME_ZONES
        .iter()
        .find(|(name, _)| *name == upper)
        .map(|&(_, m)| (hour, false, Some(m)))
        .ok_or_else(|| format!("gensky: unknown time zone \"{zone}\""))
}
