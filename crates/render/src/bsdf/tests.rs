//! Tests of the BSDFs: χ² goodness of fit of every smooth sampler, consistency of sample weights
//! and densities, delta-lobe probabilities, energy conservation, reciprocity, and the `twosided`
//! convention.

use super::*;
use crate::testing::{ChiSquareTest, Domain};
use ircache_math::{Rng, PI};
use ircache_scene::{MicrofacetDistribution, TextureDesc};
use std::sync::Arc;

/// Calls `f` with the midpoints of a 400 × 64 grid in (cos θ, φ) over the upper hemisphere,
/// cells of equal solid angle (2π over their number, which it returns).
fn upper_hemisphere_midpoints(mut f: impl FnMut(Vec3)) -> usize {
    let (nt, np) = (400, 64);
    for i in 0..nt {
        let mu = (i as f32 + 0.5) / nt as f32;
        for j in 0..np {
            let phi = 2.0 * PI * (j as f32 + 0.5) / np as f32;
            let s = (1.0 - mu * mu).sqrt();
            f(Vec3::new(s * phi.cos(), s * phi.sin(), mu));
        }
    }
    nt * np
}

/// Upper bound on the number of χ² tests in this module (for the Šidák correction).
const CHI2_TESTS: usize = 100;
const ALPHA: f64 = 0.01;

fn dir(theta_deg: f32, phi_deg: f32) -> Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

fn c(v: f32) -> TextureDesc {
    TextureDesc::Constant(Rgb::splat(v))
}

fn mat(desc: BsdfDesc) -> Bsdf {
    Material::from_desc(&desc).at(Vec2::new(0.3, 0.6))
}

fn diffuse(rho: f32) -> BsdfDesc {
    BsdfDesc::Diffuse {
        reflectance: c(rho),
    }
}

fn rough_conductor(kind: MicrofacetDistribution, au: f32, av: f32) -> BsdfDesc {
    // Gold-like complex index.
    BsdfDesc::RoughConductor {
        distribution: kind,
        alpha_u: au,
        alpha_v: av,
        eta: Rgb::new(0.143, 0.374, 1.442),
        k: Rgb::new(3.983, 2.385, 1.603),
        specular_reflectance: Rgb::ONE,
    }
}

fn mirror_rough_conductor(kind: MicrofacetDistribution, a: f32) -> BsdfDesc {
    BsdfDesc::RoughConductor {
        distribution: kind,
        alpha_u: a,
        alpha_v: a,
        eta: Rgb::ZERO,
        k: Rgb::ONE,
        specular_reflectance: Rgb::ONE,
    }
}

fn rough_plastic(kind: MicrofacetDistribution, alpha: f32, rho: f32, nonlinear: bool) -> BsdfDesc {
    BsdfDesc::RoughPlastic {
        distribution: kind,
        alpha,
        diffuse_reflectance: c(rho),
        specular_reflectance: Rgb::ONE,
        int_ior: 1.49,
        ext_ior: 1.000_277,
        nonlinear,
    }
}

fn plastic(rho: f32, nonlinear: bool) -> BsdfDesc {
    BsdfDesc::Plastic {
        diffuse_reflectance: c(rho),
        specular_reflectance: Rgb::ONE,
        int_ior: 1.49,
        ext_ior: 1.000_277,
        nonlinear,
    }
}

fn phong(kd: f32, ks: f32, n: f32) -> BsdfDesc {
    BsdfDesc::ObjPhong {
        diffuse: c(kd),
        specular: Rgb::splat(ks),
        exponent: n,
    }
}

/// Radiance's `plastic` or `metal`, two-sided as the loader makes it.
fn ward(color: f32, specularity: f32, roughness: f32, metal: bool) -> BsdfDesc {
    twosided(BsdfDesc::Ward {
        color: Rgb::new(color, color * 0.9, color * 0.8),
        specularity,
        roughness,
        metal,
        transmissivity: 0.0,
        transmitted_specular: 0.0,
        pattern: None,
        anisotropy: None,
    })
}

/// Radiance's `plastic2` or `metal2` as the loader describes it (roughness `au` along the
/// local x axis, `av` across).
fn ward_anisotropic(color: f32, specularity: f32, au: f32, av: f32, metal: bool) -> BsdfDesc {
    twosided(BsdfDesc::Ward {
        color: Rgb::new(color, color * 0.9, color * 0.8),
        specularity,
        roughness: au,
        metal,
        transmissivity: 0.0,
        transmitted_specular: 0.0,
        pattern: None,
        anisotropy: Some(ircache_scene::Anisotropy {
            roughness_v: av,
            u: Vec3::X,
        }),
    })
}

/// Radiance's `trans2` (specularity 0.04, transmissivity 0.7, transmitted specularity 0.6).
fn trans2(color: f32, au: f32, av: f32) -> BsdfDesc {
    twosided(BsdfDesc::Ward {
        color: Rgb::new(color, color * 0.9, color * 0.8),
        specularity: 0.04,
        roughness: au,
        metal: false,
        transmissivity: 0.7,
        transmitted_specular: 0.6,
        pattern: None,
        anisotropy: Some(ircache_scene::Anisotropy {
            roughness_v: av,
            u: Vec3::X,
        }),
    })
}

/// Radiance's `plastic2` or `metal2` (roughness `au` along `axis`, `av` across).
fn ward2(color: f32, specularity: f32, au: f32, av: f32, metal: bool, axis: [f32; 2]) -> Bsdf {
    let mut b = mat(ward_anisotropic(color, specularity, au, av, metal));
    if let Bsdf::TwoSided {
        front: Lobe::Ward(f),
        back: Lobe::Ward(k),
    } = &mut b
    {
        f.axis = axis;
        k.axis = axis;
    }
    b
}

/// Radiance's `trans`, two-sided as the loader makes it.
fn trans(color: f32, roughness: f32, transmissivity: f32, transmitted_specular: f32) -> BsdfDesc {
    twosided(BsdfDesc::Ward {
        color: Rgb::new(color, color * 0.9, color * 0.8),
        specularity: 0.04,
        roughness,
        metal: false,
        transmissivity,
        transmitted_specular,
        pattern: None,
        anisotropy: None,
    })
}

fn radiance_glass(transmissivity: f32, ior: f32) -> BsdfDesc {
    BsdfDesc::Glass {
        transmissivity: Rgb::splat(transmissivity),
        ior,
        pattern: None,
    }
}

fn dielectric(int_ior: f32) -> BsdfDesc {
    BsdfDesc::Dielectric {
        int_ior,
        ext_ior: 1.0,
        specular_reflectance: Rgb::ONE,
        specular_transmittance: Rgb::ONE,
    }
}

fn rough_dielectric(kind: MicrofacetDistribution, au: f32, av: f32, int_ior: f32) -> BsdfDesc {
    BsdfDesc::RoughDielectric {
        distribution: kind,
        alpha_u: au,
        alpha_v: av,
        int_ior,
        ext_ior: 1.0,
        specular_reflectance: Rgb::ONE,
        specular_transmittance: Rgb::ONE,
    }
}

fn thin_dielectric(int_ior: f32) -> BsdfDesc {
    BsdfDesc::ThinDielectric {
        int_ior,
        ext_ior: 1.0,
        specular_reflectance: Rgb::ONE,
        specular_transmittance: Rgb::ONE,
    }
}

fn conductor(eta: f32, k: f32) -> BsdfDesc {
    BsdfDesc::Conductor {
        eta: Rgb::splat(eta),
        k: Rgb::splat(k),
        specular_reflectance: Rgb::ONE,
    }
}

const KINDS: [MicrofacetDistribution; 2] = [
    MicrofacetDistribution::Beckmann,
    MicrofacetDistribution::Ggx,
];

/// Every model, with a label, for the generic checks.
fn blend(weight: f32, first: BsdfDesc, second: BsdfDesc) -> BsdfDesc {
    BsdfDesc::Blend {
        weight: c(weight),
        first: Arc::new(first),
        second: Arc::new(second),
        pattern: None,
    }
}

fn twosided(front: BsdfDesc) -> BsdfDesc {
    BsdfDesc::TwoSided {
        front: Arc::new(front),
        back: None,
    }
}

/// Mitsuba's `blendbsdf` of a white-ish diffuse and rough gold (GGX α 0.2).
fn blend_gold(weight: f32) -> BsdfDesc {
    blend(
        weight,
        diffuse(0.8),
        rough_conductor(MicrofacetDistribution::Ggx, 0.2, 0.2),
    )
}

/// Mitsuba's `principled` from its base colour, named scalar parameters (the rest at their
/// defaults) and index of refraction.
fn principled(base: Rgb, set: &[(&str, f32)], eta: f32) -> BsdfDesc {
    BsdfDesc::Principled {
        base_color: TextureDesc::Constant(base),
        parameters: Box::new(ircache_scene::PRINCIPLED_PARAMETERS.map(|(name, default)| {
            let value = set
                .iter()
                .find(|(n, _)| *n == name)
                .map_or(default, |(_, v)| *v);
            c(value)
        })),
        eta,
    }
}

/// `specular` 0.6 as Mitsuba maps it to an index of refraction.
fn eta_of_specular(specular: f32) -> f32 {
    2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0
}

/// The three principled materials checked against Mitsuba: (A) every reflection term at once,
/// (B) anisotropic with specular transmission, (C) the defaults.
fn principled_cases() -> [BsdfDesc; 3] {
    [
        principled(
            Rgb::new(0.8, 0.3, 0.2),
            &[
                ("roughness", 0.4),
                ("metallic", 0.3),
                ("spec_tint", 0.5),
                ("sheen", 0.7),
                ("sheen_tint", 0.5),
                ("clearcoat", 0.6),
                ("clearcoat_gloss", 0.4),
                ("flatness", 0.2),
            ],
            eta_of_specular(0.6),
        ),
        principled(
            Rgb::new(0.9, 0.7, 0.5),
            &[
                ("roughness", 0.25),
                ("spec_trans", 0.7),
                ("anisotropic", 0.5),
            ],
            1.4,
        ),
        principled(Rgb::splat(0.5), &[], eta_of_specular(0.5)),
    ]
}

fn all_models() -> Vec<(String, BsdfDesc)> {
    let mut v = vec![
        ("diffuse".to_string(), diffuse(0.8)),
        ("plastic".into(), plastic(0.9, false)),
        ("plastic nonlinear".into(), plastic(0.9, true)),
        ("conductor".into(), conductor(0.2, 3.0)),
        ("conductor mirror".into(), conductor(0.0, 1.0)),
        ("dielectric".into(), dielectric(1.5)),
        ("thindielectric".into(), thin_dielectric(1.5)),
        ("phong n=1".into(), phong(0.3, 0.7, 1.0)),
        ("phong n=30".into(), phong(0.5, 0.5, 30.0)),
        ("phong n=500".into(), phong(0.0, 1.0, 500.0)),
        (
            "radiance plastic α=0.05".into(),
            ward(0.8, 0.05, 0.05, false),
        ),
        ("radiance plastic α=0.3".into(), ward(0.5, 0.1, 0.3, false)),
        ("radiance metal α=0.1".into(), ward(0.9, 0.9, 0.1, true)),
        ("radiance metal α=0.6".into(), ward(0.9, 1.0, 0.6, true)),
        (
            "radiance plastic mirror".into(),
            ward(0.6, 0.05, 0.0, false),
        ),
        ("radiance metal mirror".into(), ward(0.8, 0.9, 0.0, true)),
        ("radiance trans α=0.1".into(), trans(0.8, 0.1, 0.6, 0.5)),
        ("radiance trans α=0.4".into(), trans(0.9, 0.4, 0.9, 0.3)),
        ("radiance trans smooth".into(), trans(0.8, 0.0, 0.5, 0.5)),
        ("radiance glass".into(), radiance_glass(0.96, 1.52)),
        (
            "radiance metal2 0.04/0.25".into(),
            ward_anisotropic(0.9, 0.9, 0.04, 0.25, true),
        ),
        (
            "radiance plastic2 0.3/0.06".into(),
            ward_anisotropic(0.5, 0.1, 0.3, 0.06, false),
        ),
        ("radiance trans2 0.05/0.3".into(), trans2(0.8, 0.05, 0.3)),
        ("radiance tinted glass".into(), radiance_glass(0.6, 1.52)),
    ];
    for kind in KINDS {
        for a in [0.05, 0.3, 1.0] {
            v.push((
                format!("roughconductor {kind:?} α={a}"),
                mirror_rough_conductor(kind, a),
            ));
            v.push((
                format!("roughplastic {kind:?} α={a}"),
                rough_plastic(kind, a, 0.9, false),
            ));
            v.push((
                format!("roughdielectric {kind:?} α={a}"),
                rough_dielectric(kind, a, a, 1.5),
            ));
        }
        v.push((
            format!("roughdielectric aniso {kind:?} η 1/1.33"),
            rough_dielectric(kind, 0.05, 0.4, 1.0 / 1.33),
        ));
        v.push((
            format!("roughplastic nonlinear {kind:?}"),
            rough_plastic(kind, 0.2, 0.95, true),
        ));
        v.push((
            format!("roughconductor aniso {kind:?}"),
            rough_conductor(kind, 0.05, 0.5),
        ));
    }
    for (k, desc) in principled_cases().into_iter().enumerate() {
        v.push((format!("principled {}", ["A", "B", "C"][k]), desc));
    }
    v.push(("blend diffuse/roughconductor".into(), blend_gold(0.3)));
    v.push((
        "twosided blend diffuse/roughconductor".into(),
        twosided(blend_gold(0.3)),
    ));
    v.push((
        "blend roughplastic/conductor".into(),
        blend(
            0.6,
            rough_plastic(MicrofacetDistribution::Beckmann, 0.3, 0.5, false),
            conductor(0.2, 3.0),
        ),
    ));
    v.push((
        "blend dielectric/roughconductor".into(),
        blend(
            0.5,
            dielectric(1.5),
            mirror_rough_conductor(MicrofacetDistribution::Ggx, 0.3),
        ),
    ));
    v.push((
        "blend phong/plastic".into(),
        blend(0.8, phong(0.3, 0.7, 20.0), plastic(0.5, false)),
    ));
    v.push((
        "twosided diffuse/roughconductor".into(),
        BsdfDesc::TwoSided {
            front: Arc::new(diffuse(0.5)),
            back: Some(Arc::new(mirror_rough_conductor(
                MicrofacetDistribution::Ggx,
                0.2,
            ))),
        },
    ));
    v
}

fn run_chi2(bsdf: &Bsdf, wo: Vec3, domain: Domain, label: &str) {
    let test = match domain {
        Domain::Hemisphere => ChiSquareTest::hemisphere(),
        Domain::Sphere => ChiSquareTest::sphere(),
    };
    let report = test.run(
        |u, u_lobe| {
            let s = bsdf.sample(wo, u_lobe, u)?;
            if s.delta {
                return None;
            }
            Some((s.wi, s.pdf))
        },
        |wi| bsdf.pdf(wo, wi),
    );
    report.assert_ok(ALPHA, CHI2_TESTS, label);
}

const WO_ANGLES: [(f32, f32); 4] = [(0.0, 0.0), (30.0, 70.0), (60.0, 200.0), (85.0, 300.0)];

#[test]
fn chi2_diffuse_and_plastic() {
    run_chi2(
        &mat(diffuse(0.5)),
        dir(40.0, 10.0),
        Domain::Hemisphere,
        "diffuse",
    );
    // The plastic's diffuse part: its pdf integrates to 1 − P(specular), the rest are "None".
    for (t, p) in [(10.0, 0.0), (80.0, 120.0)] {
        run_chi2(
            &mat(plastic(0.5, false)),
            dir(t, p),
            Domain::Hemisphere,
            &format!("plastic θo={t}"),
        );
    }
}

#[test]
fn chi2_radiance_plastic_and_metal() {
    for (label, desc) in [
        ("plastic α=0.05", ward(0.8, 0.05, 0.05, false)),
        ("plastic α=0.3", ward(0.5, 0.1, 0.3, false)),
        ("metal α=0.2", ward(0.9, 0.9, 0.2, true)),
    ] {
        for (t, p) in WO_ANGLES {
            run_chi2(
                &mat(desc.clone()),
                dir(t, p),
                Domain::Hemisphere,
                &format!("{label} θo={t}"),
            );
        }
    }
    for (label, desc) in [
        ("trans α=0.1", trans(0.8, 0.1, 0.6, 0.5)),
        ("trans α=0.4", trans(0.9, 0.4, 0.9, 0.3)),
    ] {
        for (t, p) in WO_ANGLES {
            run_chi2(
                &mat(desc.clone()),
                dir(t, p),
                Domain::Sphere,
                &format!("{label} θo={t}"),
            );
        }
    }
}

/// Radiance's plastic and metal against `normal.c`'s own arithmetic: the W-G-M-D lobe at a
/// hand-picked pair of directions, the diffuse part, and the Fresnel estimate of a smooth one.
#[test]
fn radiance_plastic_matches_normal_c() {
    use crate::bsdf::ward::fresnel_estimate;
    let b = mat(ward(0.5, 0.04, 0.2, false));
    let (wo, wi) = (dir(30.0, 0.0), dir(50.0, 180.0));
    // normal.c: h = l + v, d2 = (h·n)², d3 = h·h, exp(−(d3 − d2)/(d2 α²)) d3 / (π d2² α²).
    let h = wo + wi;
    let (d2, d3) = (h.z * h.z, h.dot(h));
    let spec = (-(d3 - d2) / (d2 * 0.04)).exp() * d3 / (std::f32::consts::PI * d2 * d2 * 0.04);
    let expect = (0.5 * 0.96 / std::f32::consts::PI + 0.04 * spec) * wi.z;
    let got = b.eval(wo, wi).r;
    assert!((got - expect).abs() < 1e-5 * expect, "{got} vs {expect}");
    // A smooth plastic: the mirror weighs s + F(μ)(1 − s), the diffuse part c (1 − s').
    let b = mat(ward(0.5, 0.05, 0.0, false));
    let wo = dir(70.0, 0.0);
    let f = fresnel_estimate(wo.z);
    let s = 0.05 + f * 0.95;
    let wi = dir(20.0, 90.0);
    let expect = 0.5 * (1.0 - s) / std::f32::consts::PI * (1.0 - fresnel_estimate(wi.z)) * wi.z;
    assert!((b.eval(wo, wi).r - expect).abs() < 1e-6);
    let mirror = (0..64)
        .filter_map(|k| b.sample(wo, (k as f32 + 0.5) / 64.0, Vec2::new(0.3, 0.6)))
        .find(|x| x.delta)
        .expect("the mirror lobe is sampled");
    assert!((mirror.weight.r * mirror.pdf - s).abs() < 1e-5);
}

/// Radiance's glass: without absorption the sheet's reflectance is 2r/(1 + r) per polarisation
/// (r its Fresnel reflectance) and reflection and transmission add up to one; with it, less.
#[test]
fn radiance_glass_matches_glass_c() {
    use crate::bsdf::ThinDielectric;
    let sheet = |t: f32| ThinDielectric {
        eta: 1.52,
        specular_reflectance: Rgb::ONE,
        specular_transmittance: Rgb::ONE,
        transmissivity: Some(Rgb::splat(t)),
    };
    let r = ((1.52f32 - 1.0) / 2.52).powi(2);
    for u in [0.01, 0.99] {
        let c = sheet(1.0).choose(1.0, u);
        let value = c.weight.r * c.prob;
        let expect = if c.reflected {
            2.0 * r / (1.0 + r)
        } else {
            1.0 - 2.0 * r / (1.0 + r)
        };
        assert!((value - expect).abs() < 1e-5, "{c:?}");
    }
    for cos in [1.0f32, 0.5, 0.1] {
        let (tr, re) = (sheet(0.9).transmittance(cos).r, {
            let c = sheet(0.9).choose(cos, 0.0);
            c.weight.r * c.prob
        });
        assert!(tr + re < 1.0 && tr > 0.0 && re > 0.0);
        // 88 % transmittance glass is 0.96 transmissivity (glass.c's comment).
        if cos == 1.0 {
            assert!((sheet(0.96).transmittance(1.0).r - 0.88).abs() < 0.003);
        }
    }
}

#[test]
fn chi2_roughconductor_isotropic() {
    for kind in KINDS {
        for a in [0.1, 0.4, 1.0] {
            for (t, p) in WO_ANGLES {
                let label = format!("roughconductor {kind:?} α={a} θo={t}");
                run_chi2(
                    &mat(rough_conductor(kind, a, a)),
                    dir(t, p),
                    Domain::Hemisphere,
                    &label,
                );
            }
        }
    }
}

#[test]
fn chi2_roughconductor_anisotropic() {
    for kind in KINDS {
        for (au, av) in [(0.1, 0.5), (0.7, 0.2)] {
            for (t, p) in WO_ANGLES {
                let label = format!("roughconductor {kind:?} α=({au},{av}) θo={t}");
                run_chi2(
                    &mat(rough_conductor(kind, au, av)),
                    dir(t, p),
                    Domain::Hemisphere,
                    &label,
                );
            }
        }
    }
}

#[test]
fn chi2_roughplastic() {
    for kind in KINDS {
        for a in [0.1, 0.5] {
            for (t, p) in [(20.0, 30.0), (75.0, 250.0)] {
                let label = format!("roughplastic {kind:?} α={a} θo={t}");
                run_chi2(
                    &mat(rough_plastic(kind, a, 0.5, false)),
                    dir(t, p),
                    Domain::Hemisphere,
                    &label,
                );
            }
        }
    }
}

/// Rough glass samples both hemispheres: from outside and from inside (η seen inverted there,
/// with total internal reflection at the grazing view).
#[test]
fn chi2_roughdielectric() {
    for kind in KINDS {
        for (au, av) in [(0.1, 0.1), (0.5, 0.2)] {
            for (t, p) in [(10.0, 0.0), (70.0, 40.0), (150.0, 100.0), (100.0, 300.0)] {
                let label = format!("roughdielectric {kind:?} α=({au}, {av}) θo={t}");
                run_chi2(
                    &mat(rough_dielectric(kind, au, av, 1.5)),
                    dir(t, p),
                    Domain::Sphere,
                    &label,
                );
            }
        }
    }
}

/// Rough dielectric against Mitsuba 3.9.1's own `roughdielectric` (`scalar_rgb`, `BSDF::eval`
/// with the cosine and `BSDF::pdf`, int_ior 1.5, ext_ior 1, φ in degrees): reflection and
/// refraction from outside and inside, and a pair no microfacet joins. Mitsuba's Beckmann
/// masking is a rational fit within 0.35 % of the exact one used here.
#[test]
fn roughdielectric_matches_mitsuba() {
    // (θo, φo, θi, φi, f·|cos θi|, pdf) with θ from the +z normal.
    type Values = [(f32, f32, f32, f32, f32, f32); 7];
    let cases: [(MicrofacetDistribution, f32, f32, Values); 2] = [
        (
            MicrofacetDistribution::Ggx,
            0.2,
            1e-3,
            [
                (30.0, 0.0, 40.0, 180.0, 0.07003672, 0.07052641),
                (30.0, 0.0, 150.0, 180.0, 0.715342, 1.614867),
                (60.0, 10.0, 170.0, 200.0, 0.0, 0.0),
                (150.0, 0.0, 20.0, 180.0, 0.2635359, 0.117282),
                (160.0, 30.0, 120.0, 220.0, 0.031855, 0.03278358),
                (80.0, 0.0, 100.0, 180.0, 0.189261, 0.5348793),
                (45.0, 0.0, 135.0, 180.0, 0.2507212, 0.5697086),
            ],
        ),
        (
            MicrofacetDistribution::Beckmann,
            0.3,
            1e-2,
            [
                (30.0, 0.0, 40.0, 180.0, 0.04099753, 0.04099753),
                (30.0, 0.0, 150.0, 180.0, 0.6867325, 1.545148),
                (60.0, 10.0, 170.0, 200.0, 0.0, 0.0),
                (150.0, 0.0, 20.0, 180.0, 7.825976e-05, 3.478212e-05),
                (160.0, 30.0, 120.0, 220.0, 0.06233995, 0.06233994),
                (80.0, 0.0, 100.0, 180.0, 0.0, 0.0),
                (45.0, 0.0, 135.0, 180.0, 0.001148204, 0.00258346),
            ],
        ),
    ];
    for (kind, alpha, tolerance, values) in cases {
        let b = mat(rough_dielectric(kind, alpha, alpha, 1.5));
        for (to, po, ti, pi, f, pdf) in values {
            let (wo, wi) = (dir(to, po), dir(ti, pi));
            let close = |ours: f32, theirs: f32| {
                if theirs == 0.0 {
                    ours == 0.0
                } else {
                    (ours / theirs - 1.0).abs() < tolerance
                }
            };
            let (ours_f, ours_pdf) = (b.eval(wo, wi).r, b.pdf(wo, wi));
            assert!(
                close(ours_f, f) && close(ours_pdf, pdf),
                "{kind:?} α {alpha}, ({to}, {po}) → ({ti}, {pi}): f {ours_f} pdf {ours_pdf} against Mitsuba's {f} {pdf}"
            );
        }
    }
}

/// Nearly smooth rough glass loses almost nothing (its albedo, with the radiance scaling of
/// refraction undone, tends to 1) and reflects as often as the smooth interface's Fresnel term
/// says; it is traced, never served by a cache (no Lambertian part, no radiance-cache table).
#[test]
fn roughdielectric_tends_to_smooth_glass() {
    let rough = mat(rough_dielectric(
        MicrofacetDistribution::Ggx,
        0.01,
        0.01,
        1.5,
    ));
    let n = 100_000;
    // Inside, away from the critical angle (41.8°), where Fresnel is too steep for α's spread.
    for theta in [0.0f32, 40.0, 70.0, 160.0, 175.0] {
        let wo = dir(theta, 20.0);
        let r = fresnel::fresnel_dielectric(wo.z, 1.5).r;
        let mut rng = Rng::new(41, 42);
        let (mut energy, mut reflected) = (0.0f64, 0usize);
        for _ in 0..n {
            let Some(s) = rough.sample(wo, rng.next_f32(), rng.next_2d()) else {
                continue;
            };
            energy += f64::from(s.weight.r * s.eta * s.eta);
            reflected += usize::from(s.wi.z * wo.z > 0.0);
        }
        let energy = energy / n as f64;
        let reflected = reflected as f64 / n as f64;
        assert!((energy - 1.0).abs() < 0.01, "θo {theta}: albedo {energy}");
        let sigma = (f64::from(r) * (1.0 - f64::from(r)) / n as f64).sqrt();
        assert!(
            (reflected - f64::from(r)).abs() < 5.0 * sigma + 2e-3,
            "θo {theta}: reflected {reflected} against Fresnel {r}"
        );
    }
    assert!(rough.has_smooth() && !rough.has_delta() && rough.transmits());
    assert!(rough.lambertian_albedo(dir(30.0, 0.0)).is_black());
    assert!(crate::radiance_cache::brdf::order_for(&rough, 10, 0.95).is_none());
}

#[test]
fn chi2_phong_and_twosided() {
    for (kd, ks, n) in [(0.5, 0.5, 1.0), (0.2, 0.8, 20.0), (0.1, 0.6, 150.0)] {
        for (t, p) in [(0.0, 0.0), (50.0, 100.0)] {
            let label = format!("phong kd={kd} ks={ks} n={n} θo={t}");
            run_chi2(
                &mat(phong(kd, ks, n)),
                dir(t, p),
                Domain::Hemisphere,
                &label,
            );
        }
    }
    // Back side of a twosided rough conductor: samples land in the lower hemisphere.
    let b = mat(BsdfDesc::TwoSided {
        front: Arc::new(diffuse(0.5)),
        back: Some(Arc::new(rough_conductor(
            MicrofacetDistribution::Ggx,
            0.3,
            0.3,
        ))),
    });
    run_chi2(&b, -dir(30.0, 40.0), Domain::Sphere, "twosided back");
    run_chi2(&b, dir(30.0, 40.0), Domain::Sphere, "twosided front");
}

/// For every smooth sample: `pdf == pdf(wo, wi)`, `weight == eval / pdf`, unit direction,
/// `eval` finite and non-negative.
#[test]
fn sample_weights_match_eval_over_pdf() {
    let mut rng = Rng::new(11, 12);
    for (label, desc) in all_models() {
        let b = mat(desc);
        for k in 0..40 {
            let mut wo = ircache_math::sampling::square_to_uniform_sphere(rng.next_2d());
            if k % 4 == 0 {
                wo.z = wo.z.abs();
            }
            for _ in 0..500 {
                let Some(s) = b.sample(wo, rng.next_f32(), rng.next_2d()) else {
                    continue;
                };
                assert!(
                    (s.wi.length() - 1.0).abs() < 1e-4,
                    "{label}: |wi| = {}",
                    s.wi.length()
                );
                assert!(
                    s.weight.is_valid_radiance() && s.pdf > 0.0 && s.pdf.is_finite(),
                    "{label}: {s:?}"
                );
                if s.delta {
                    assert!(s.pdf <= 1.0 + 1e-6, "{label}");
                    continue;
                }
                let pdf = b.pdf(wo, s.wi);
                let f = b.eval(wo, s.wi);
                assert!(f.is_valid_radiance(), "{label}");
                assert!(
                    (pdf - s.pdf).abs() <= 1e-4 * pdf.max(s.pdf),
                    "{label}: pdf {} vs {pdf}",
                    s.pdf
                );
                let expect = f / pdf;
                for ch in 0..3 {
                    let (a, e) = (s.weight[ch], expect[ch]);
                    assert!(
                        (a - e).abs() <= 1e-3 * e.abs().max(1e-3),
                        "{label}: weight {a} vs eval/pdf {e}, wo {wo}"
                    );
                }
            }
        }
    }
}

/// Monte Carlo albedo `∫ eval dωi` (by the sample weights) is at most 1 (+3σ) for unit-scale
/// materials, from many directions.
#[test]
fn energy_conservation() {
    let mut rng = Rng::new(21, 22);
    let n = 100_000;
    for (label, desc) in all_models() {
        let b = mat(desc);
        for theta in [0.0f32, 20.0, 45.0, 70.0, 85.0, 89.5, 120.0, 170.0] {
            let wo = dir(theta, 37.0);
            let mut sum = [0.0f64; 3];
            let mut sum2 = [0.0f64; 3];
            for _ in 0..n {
                let Some(s) = b.sample(wo, rng.next_f32(), rng.next_2d()) else {
                    continue;
                };
                // Undo the 1/η² radiance scaling of refraction: energy, not radiance, is conserved.
                let w = if s.eta != 1.0 {
                    s.weight * (s.eta * s.eta)
                } else {
                    s.weight
                };
                for ch in 0..3 {
                    sum[ch] += f64::from(w[ch]);
                    sum2[ch] += f64::from(w[ch]) * f64::from(w[ch]);
                }
            }
            // Burley's model, Mitsuba's `principled` included, gains a little at grazing
            // views (its sheen and retro-reflection; 1.5 % measured at 85°).
            let bound = if label.starts_with("principled") {
                1.03
            } else {
                1.0
            };
            for ch in 0..3 {
                let mean = sum[ch] / n as f64;
                let var = (sum2[ch] / n as f64 - mean * mean).max(0.0);
                let sigma = (var / n as f64).sqrt();
                assert!(
                    mean <= bound + 3.0 * sigma + 1e-4,
                    "{label} θo={theta}: albedo {mean} ± {sigma}"
                );
            }
        }
    }
}

/// Estimate of the albedo with its standard error, channel 0.
fn albedo(b: &Bsdf, wo: Vec3, n: usize, seed: u64) -> (f64, f64) {
    let mut rng = Rng::new(seed, 1);
    let (mut s, mut s2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        if let Some(x) = b.sample(wo, rng.next_f32(), rng.next_2d()) {
            let w = f64::from(x.weight.r);
            s += w;
            s2 += w * w;
        }
    }
    let m = s / n as f64;
    (m, ((s2 / n as f64 - m * m).max(0.0) / n as f64).sqrt())
}

#[test]
fn white_furnace_checks() {
    // Diffuse: every weight is exactly ρ, and ∫ eval = ρ by quadrature too.
    let b = mat(diffuse(0.7));
    let (m, s) = albedo(&b, dir(50.0, 0.0), 10_000, 1);
    assert!((m - 0.7).abs() < 1e-6 && s < 1e-6);
    // Perfect mirror conductor: weight 1.
    let b = mat(conductor(0.0, 1.0));
    let (m, _) = albedo(&b, dir(80.0, 0.0), 1000, 2);
    assert!((m - 1.0).abs() < 1e-6);
    // Very large k: also a mirror.
    let b = mat(conductor(1.0, 1e4));
    let (m, _) = albedo(&b, dir(60.0, 0.0), 1000, 3);
    assert!((m - 1.0).abs() < 1e-3, "{m}");
    // Rough mirrors: nearly lossless when smooth, lossy (but ≤ 1) when very rough.
    for kind in KINDS {
        let (m, s) = albedo(
            &mat(mirror_rough_conductor(kind, 0.05)),
            dir(30.0, 0.0),
            100_000,
            4,
        );
        assert!(m > 0.99 && m <= 1.0 + 3.0 * s, "{kind:?} α=0.05: {m}");
        let (m, s) = albedo(
            &mat(mirror_rough_conductor(kind, 1.0)),
            dir(60.0, 0.0),
            100_000,
            5,
        );
        assert!(
            m < 0.97 && m > 0.3 && m <= 1.0 + 3.0 * s,
            "{kind:?} α=1: {m}"
        );
    }
    // Smooth dielectric: the delta lobes' probabilities sum to 1 and their weights are the unit
    // scales, times (η_i/η_t)² for refraction.
    for theta in [0.0f32, 40.0, 80.0, 140.0, 175.0] {
        let b = mat(dielectric(1.5));
        let wo = dir(theta, 20.0);
        let r = fresnel::fresnel_dielectric(wo.z, 1.5);
        let refl = b.sample(wo, 0.0, Vec2::ZERO).unwrap();
        assert!(refl.delta && (refl.pdf - r.r).abs() < 1e-6 && refl.weight == Rgb::ONE);
        if r.r < 1.0 {
            let tr = b.sample(wo, 0.999_999, Vec2::ZERO).unwrap();
            assert!((refl.pdf + tr.pdf - 1.0).abs() < 1e-6);
            assert!(
                (tr.weight.r - r.eta_ti * r.eta_ti).abs() < 1e-5
                    && (tr.eta - r.eta_it).abs() < 1e-6
            );
            // Snell's law and opposite side.
            let sin_o = (1.0 - wo.z * wo.z).sqrt();
            let sin_i = (1.0 - tr.wi.z * tr.wi.z).sqrt();
            assert!((sin_i - sin_o * r.eta_ti).abs() < 1e-5 && tr.wi.z * wo.z < 0.0);
            // Reversibility: refracting back gives −wo's mirror... i.e. the original direction.
            let back = b.sample(tr.wi, 0.999_999, Vec2::ZERO).unwrap();
            assert!((back.wi - wo).length() < 1e-4, "{} vs {wo}", back.wi);
            assert!((back.weight.r * tr.weight.r - 1.0).abs() < 1e-4);
        }
    }
}

/// Delta-lobe choice frequencies match the analytic probabilities (within 4.5σ).
#[test]
fn delta_sampling_probabilities() {
    let n = 200_000;
    let check = |b: &Bsdf, wo: Vec3, expected: f64, label: &str| {
        let mut rng = Rng::new(31, 32);
        let mut hits = 0usize;
        for _ in 0..n {
            if let Some(s) = b.sample(wo, rng.next_f32(), rng.next_2d()) {
                if s.delta && s.wi.z * wo.z > 0.0 {
                    hits += 1;
                }
            }
        }
        let f = hits as f64 / n as f64;
        let sigma = (expected * (1.0 - expected) / n as f64).sqrt().max(1e-9);
        assert!(
            (f - expected).abs() <= 4.5 * sigma + 1e-6,
            "{label}: {f} vs {expected}"
        );
    };
    for theta in [0.0f32, 45.0, 75.0, 89.0] {
        let wo = dir(theta, 10.0);
        // Dielectric: P(reflection) = R.
        let r = fresnel::fresnel_dielectric(wo.z, 1.5).r;
        check(&mat(dielectric(1.5)), wo, f64::from(r), "dielectric");
        let r_in = fresnel::fresnel_dielectric(-wo.z, 1.5).r;
        check(
            &mat(dielectric(1.5)),
            -wo,
            f64::from(r_in),
            "dielectric inside",
        );
        // Thin dielectric: P = 2R/(1+R).
        check(
            &mat(thin_dielectric(1.5)),
            wo,
            f64::from(2.0 * r / (1.0 + r)),
            "thin",
        );
        // Plastic: P(spec) = F·w_s / (F·w_s + (1−F)(1−w_s)), w_s = 1/(1 + ρ̄).
        let rho = 0.6;
        let f = fresnel::fresnel_dielectric(wo.z, 1.49 / 1.000_277).r;
        let ws = 1.0 / (1.0 + rho);
        let p = f * ws / (f * ws + (1.0 - f) * (1.0 - ws));
        check(&mat(plastic(rho, false)), wo, f64::from(p), "plastic");
        // Conductor: always the delta, weight F.
        let b = mat(conductor(0.2, 3.0));
        let s = b.sample(wo, 0.5, Vec2::splat(0.5)).unwrap();
        let fc = fresnel::fresnel_conductor_1(wo.z, 0.2, 3.0);
        assert!(s.delta && s.pdf == 1.0 && (s.weight.g - fc).abs() < 1e-6);
        assert!((s.wi - fresnel::reflect(wo)).length() < 1e-6);
    }
    // Thin dielectric transmission goes straight through.
    let wo = dir(50.0, 10.0);
    let s = mat(thin_dielectric(1.5))
        .sample(wo, 0.999, Vec2::ZERO)
        .unwrap();
    assert!((s.wi + wo).length() < 1e-6 && s.eta == 1.0);
}

/// `eval(wo, wi)/|cos θi| = eval(wi, wo)/|cos θo|` for the reflection models.
#[test]
fn reciprocity() {
    let mut rng = Rng::new(41, 42);
    for (label, desc) in all_models() {
        let b = mat(desc);
        if !b.has_smooth() {
            continue;
        }
        for _ in 0..2000 {
            let wo = ircache_math::sampling::square_to_uniform_hemisphere(rng.next_2d());
            let wi = ircache_math::sampling::square_to_uniform_hemisphere(rng.next_2d());
            if wo.z < 1e-3 || wi.z < 1e-3 {
                continue;
            }
            let a = b.eval(wo, wi) / wi.z;
            let c = b.eval(wi, wo) / wo.z;
            for ch in 0..3 {
                // Rough plastic's transmittance table is interpolated linearly: exact symmetry.
                assert!(
                    (a[ch] - c[ch]).abs() <= 2e-4 * a[ch].max(c[ch]) + 1e-7,
                    "{label}: {a:?} vs {c:?}"
                );
            }
        }
    }
}

#[test]
fn one_sided_and_two_sided_conventions() {
    let up = dir(30.0, 0.0);
    let down = -dir(40.0, 90.0);
    for (label, desc) in all_models() {
        let b = mat(desc.clone());
        if b.transmits() || matches!(desc, BsdfDesc::TwoSided { .. }) {
            continue;
        }
        // One-sided: black from below, and no transmission.
        assert!(
            b.eval(down, up).is_black() && b.eval(up, down).is_black(),
            "{label}"
        );
        assert!(b.sample(down, 0.3, Vec2::splat(0.4)).is_none(), "{label}");
        assert_eq!(b.pdf(down, up), 0.0);
        // Twosided: the back mirrors the front.
        let t = mat(BsdfDesc::TwoSided {
            front: Arc::new(desc),
            back: None,
        });
        let w1 = dir(20.0, 50.0);
        let w2 = dir(60.0, 250.0);
        let flip = |w: Vec3| Vec3::new(w.x, w.y, -w.z);
        assert_eq!(t.eval(flip(w1), flip(w2)), b.eval(w1, w2), "{label}");
        assert_eq!(t.pdf(flip(w1), flip(w2)), b.pdf(w1, w2), "{label}");
        assert!(t.eval(flip(w1), w2).is_black(), "{label}");
        if let Some(s) = t.sample(flip(w1), 0.3, Vec2::new(0.2, 0.7)) {
            assert!(s.wi.z < 0.0, "{label}");
        }
    }
    // Different back model.
    let t = mat(BsdfDesc::TwoSided {
        front: Arc::new(diffuse(0.2)),
        back: Some(Arc::new(diffuse(0.6))),
    });
    let (w1, w2) = (dir(20.0, 0.0), dir(30.0, 0.0));
    assert!((t.eval(w1, w2).r - 0.2 * w2.z / PI).abs() < 1e-6);
    assert!((t.eval(-w1, -w2).r - 0.6 * w2.z / PI).abs() < 1e-6);
    assert!(t.is_diffuse_only() && (t.diffuse_reflectance().r - 0.2).abs() < 1e-7);
    assert!(Material::from_desc(&BsdfDesc::TwoSided {
        front: Arc::new(diffuse(0.2)),
        back: None
    })
    .is_two_sided());
}

#[test]
fn classification() {
    assert!(mat(diffuse(0.5)).is_diffuse_only());
    assert!(!mat(plastic(0.5, false)).is_diffuse_only());
    assert!(mat(plastic(0.5, false)).has_smooth());
    assert!(!mat(conductor(0.0, 1.0)).has_smooth());
    assert!(!mat(dielectric(1.5)).has_smooth());
    assert!(!mat(thin_dielectric(1.5)).has_smooth());
    assert!((mat(plastic(0.4, false)).diffuse_reflectance().g - 0.4).abs() < 1e-7);
    assert!((mat(phong(0.3, 0.5, 10.0)).diffuse_reflectance().g - 0.3).abs() < 1e-7);
    assert!(mat(conductor(0.0, 1.0)).diffuse_reflectance().is_black());
    // Diffuse eval against the formula.
    let b = mat(diffuse(0.5));
    let (wo, wi) = (dir(10.0, 0.0), dir(60.0, 90.0));
    assert!((b.eval(wo, wi).r - 0.5 * wi.z / PI).abs() < 1e-7);
}

/// Rough plastic with α → 0 approaches the smooth plastic's diffuse part, and its Lambertian base
/// is textured.
#[test]
fn roughplastic_matches_plastic_when_smooth_and_uses_textures() {
    let rough = mat(rough_plastic(
        MicrofacetDistribution::Ggx,
        0.001,
        0.5,
        false,
    ));
    let smooth = mat(plastic(0.5, false));
    let (wo, wi) = (dir(30.0, 0.0), dir(50.0, 120.0));
    let (a, b) = (rough.eval(wo, wi).r, smooth.eval(wo, wi).r);
    // Within the difference between the tabulated internal reflectance and the F_dr fit.
    assert!((a - b).abs() < 0.05 * b, "{a} vs {b}");
    // A bitmap-textured base.
    let mut img = ircache_image::Image::new(2, 1);
    img.set(0, 0, Rgb::splat(0.1));
    img.set(1, 0, Rgb::splat(0.9));
    let tex = TextureDesc::Bitmap(Arc::new(ircache_scene::BitmapDesc {
        path: "t.png".into(),
        image: Arc::new(img),
        filter: ircache_scene::TextureFilter::Nearest,
        wrap: ircache_scene::WrapMode::Repeat,
        to_uv: ircache_math::Mat3::IDENTITY,
    }));
    let m = Material::from_desc(&BsdfDesc::Diffuse { reflectance: tex });
    assert!((m.at(Vec2::new(0.25, 0.5)).diffuse_reflectance().r - 0.1).abs() < 1e-7);
    assert!((m.at(Vec2::new(0.75, 0.5)).diffuse_reflectance().r - 0.9).abs() < 1e-7);
    assert!((m.mean_diffuse_reflectance().r - 0.5).abs() < 1e-6);
}

/// The χ² test has power: a 10 % error in the claimed roughness, or the wrong distribution, is
/// detected.
#[test]
fn chi2_detects_wrong_densities() {
    let wo = dir(40.0, 30.0);
    let sampler = mat(rough_conductor(MicrofacetDistribution::Ggx, 0.3, 0.3));
    let claimed = mat(rough_conductor(MicrofacetDistribution::Ggx, 0.33, 0.33));
    let report = ChiSquareTest::hemisphere().run(
        |u, l| sampler.sample(wo, l, u).map(|s| (s.wi, 0.0)),
        |wi| claimed.pdf(wo, wi),
    );
    assert!(!report.passes(ALPHA, CHI2_TESTS), "{}", report.table());
    // Beckmann samples judged against GGX densities.
    let sampler = mat(rough_conductor(MicrofacetDistribution::Beckmann, 0.3, 0.3));
    let report = ChiSquareTest::hemisphere().run(
        |u, l| sampler.sample(wo, l, u).map(|s| (s.wi, 0.0)),
        |wi| claimed.pdf(wo, wi),
    );
    assert!(!report.passes(ALPHA, CHI2_TESTS));
}

#[test]
fn roughplastic_tables_are_quick_to_build() {
    let t0 = std::time::Instant::now();
    for kind in KINDS {
        let _ = Material::from_desc(&rough_plastic(kind, 0.3, 0.5, false));
    }
    // Generous bound (optimised test profile): scenes build one table per rough plastic.
    assert!(t0.elapsed().as_secs_f32() < 5.0, "{:?}", t0.elapsed());
    eprintln!("two rough plastic tables: {:?}", t0.elapsed());
}

/// The caching split `f = k(wo)/π + f_glossy`: the glossy sampler's weights and densities agree
/// with `eval_glossy`/`pdf_glossy`; and the Lambertian part's albedo under uniform light,
/// `∫ (eval − eval_glossy) dωi` by quadrature, equals `k(wo)` (exactly for diffuse and Phong;
/// for plastics `k` uses the mean entering transmittance, which is exact under uniform light).
#[test]
fn glossy_split_is_consistent() {
    let mut rng = Rng::new(31, 32);
    for (label, desc) in all_models() {
        let b = mat(desc);
        for &(t, p) in &WO_ANGLES[..3] {
            let wo = dir(t, p);
            // Sampler agrees with eval/pdf of the glossy part.
            for _ in 0..300 {
                let Some(s) = b.sample_glossy(wo, rng.next_f32(), rng.next_2d()) else {
                    continue;
                };
                assert!(s.weight.is_valid_radiance(), "{label}: {s:?}");
                if s.delta {
                    continue;
                }
                let pdf = b.pdf_glossy(wo, s.wi);
                assert!(
                    (pdf - s.pdf).abs() <= 1e-3 * pdf.max(s.pdf),
                    "{label}: pdf {} vs {pdf}",
                    s.pdf
                );
                let expect = b.eval_glossy(wo, s.wi) / pdf;
                for ch in 0..3 {
                    let (a, e) = (s.weight[ch], expect[ch]);
                    assert!(
                        (a - e).abs() <= 1e-3 * e.abs().max(1e-3),
                        "{label}: weight {a} vs {e}"
                    );
                }
            }
            // ∫ (eval − eval_glossy) dωi over the upper hemisphere by a midpoint rule in
            // (cos θ, φ).
            let mut sum = Rgb::ZERO;
            let n = upper_hemisphere_midpoints(|wi| sum += b.eval(wo, wi) - b.eval_glossy(wo, wi));
            let lambert = sum * (2.0 * PI / n as f32);
            let k = b.lambertian_albedo(wo);
            for ch in 0..3 {
                assert!(
                    (lambert[ch] - k[ch]).abs() <= 5e-3 * k[ch].max(0.05),
                    "{label} θo={t}: ∫ f_lambert = {} vs k = {}",
                    lambert[ch],
                    k[ch]
                );
            }
        }
    }
}

/// Rough plastic against Mitsuba 3.9.1's own `roughplastic` (`scalar_rgb`, `BSDF::eval` with the
/// cosine) at grazing and ordinary angles, φ 90° apart: the coating's transmittance must be
/// Mitsuba's `eval_transmittance` (refraction masked by G1), not `1 − R`, which was 9–14 % too
/// bright at 80–85° from the normal.
#[test]
fn roughplastic_matches_mitsuba_at_grazing_angles() {
    // (θo, θi, Mitsuba's value) per (distribution, α, ρ).
    type Values = [(f32, f32, f32); 5];
    let cases: [(MicrofacetDistribution, f32, f32, Values); 2] = [
        (
            MicrofacetDistribution::Ggx,
            0.1,
            0.725,
            [
                (80.0, 60.0, 0.071_933_31),
                (85.0, 20.0, 0.125_180_33),
                (45.0, 45.0, 0.145_729_48),
                (10.0, 70.0, 0.063_145_16),
                (60.0, 60.0, 0.094_559_34),
            ],
        ),
        (
            MicrofacetDistribution::Beckmann,
            0.3,
            0.6,
            [
                (80.0, 60.0, 0.062_901_09),
                (85.0, 20.0, 0.118_377_23),
                (45.0, 45.0, 0.114_345_6),
                (10.0, 70.0, 0.050_610_04),
                (60.0, 60.0, 0.073_638_37),
            ],
        ),
    ];
    for (kind, alpha, rho, values) in cases {
        let m = mat(rough_plastic(kind, alpha, rho, false));
        for (theta_o, theta_i, mitsuba) in values {
            let ours = m.eval(dir(theta_o, 0.0), dir(theta_i, 90.0)).r;
            assert!(
                (ours / mitsuba - 1.0).abs() < 1e-3,
                "{kind:?} α {alpha}, θo {theta_o} θi {theta_i}: {ours} against Mitsuba's {mitsuba}"
            );
        }
    }
}

/// What light samples of a cached environment estimate (`EnvironmentServed::remainder`): with
/// the Lambertian and glossy parts served, the rest integrates to zero under uniform light on
/// every model (the Lambertian stand-in is exact there), and on a Lambertian surface it is zero
/// in every direction (no light sample needed).
#[test]
fn the_environment_left_to_light_samples_integrates_to_zero_where_the_cache_serves_all() {
    use crate::integrators::light_sampling::EnvironmentServed;
    for (label, desc) in all_models() {
        let b = mat(desc);
        if !b.has_smooth() {
            continue;
        }
        let diffuse_only = b.is_diffuse_only();
        for t in [0.0f32, 40.0, 75.0] {
            let wo = dir(t, 30.0);
            let served = EnvironmentServed {
                lambertian: b.lambertian_albedo(wo),
                glossy: true,
            };
            let (mut rest, mut whole) = (Rgb::ZERO, Rgb::ZERO);
            let n = upper_hemisphere_midpoints(|wi| {
                let f = b.eval(wo, wi);
                let r = served.remainder(&b, wo, wi, f);
                if diffuse_only {
                    assert!(r.is_black(), "{label}: {r:?} left at {wi:?}");
                }
                rest += r;
                whole += f;
            });
            for ch in 0..3 {
                assert!(
                    rest[ch].abs() <= 5e-3 * whole[ch].max(0.05 * n as f32),
                    "{label} θo={t}: ∫ rest = {} of ∫ f = {}",
                    rest[ch],
                    whole[ch]
                );
            }
        }
    }
}

/// `blendbsdf` against Mitsuba 3.9.1's own (`scalar_rgb`, `eval` with the cosine, red and blue,
/// and `pdf`): a `twosided` blend of diffuse and rough gold (weight 0.3, seen from both sides)
/// and a one-sided blend of Beckmann rough plastic and GGX rough gold (weight 0.6).
#[test]
fn blend_matches_mitsuba() {
    // (θo, φo, θi, φi, f·cos red, blue, pdf).
    type Values = [(f32, f32, f32, f32, f32, f32, f32); 6];
    let twosided_gold: Values = [
        (30.0, 0.0, 40.0, 180.0, 0.6080251, 0.296593, 0.6620703),
        (10.0, 0.0, 70.0, 90.0, 0.06743071, 0.06316119, 0.08337031),
        (60.0, 10.0, 55.0, 200.0, 0.5990704, 0.2883642, 0.654039),
        (80.0, 0.0, 75.0, 180.0, 2.184749, 1.244286, 2.560232),
        (150.0, 0.0, 160.0, 180.0, 0.6418278, 0.3269917, 0.7007622),
        (0.0, 0.0, 30.0, 45.0, 0.2389343, 0.1827284, 0.2807334),
    ];
    let plastic_gold: Values = [
        (30.0, 0.0, 40.0, 180.0, 0.3536289, 0.1582527, 0.4352318),
        (10.0, 0.0, 70.0, 90.0, 0.04704339, 0.02712676, 0.07925812),
        (60.0, 10.0, 55.0, 200.0, 0.4669589, 0.2205195, 0.6039704),
        (80.0, 0.0, 75.0, 180.0, 1.198763, 0.9062548, 1.642565),
        (150.0, 0.0, 160.0, 180.0, 0.0, 0.0, 0.0),
        (0.0, 0.0, 30.0, 45.0, 0.2109003, 0.1073198, 0.279042),
    ];
    let plastic = BsdfDesc::RoughPlastic {
        distribution: MicrofacetDistribution::Beckmann,
        alpha: 0.3,
        diffuse_reflectance: c(0.5),
        specular_reflectance: Rgb::ONE,
        int_ior: 1.49,
        ext_ior: 1.000_277,
        nonlinear: false,
    };
    let cases = [
        (
            "twosided blend",
            mat(twosided(blend_gold(0.3))),
            twosided_gold,
        ),
        (
            "blend",
            mat(blend(
                0.6,
                plastic,
                rough_conductor(MicrofacetDistribution::Ggx, 0.4, 0.4),
            )),
            plastic_gold,
        ),
    ];
    for (label, b, values) in cases {
        for (to, po, ti, pi, red, blue, pdf) in values {
            let (wo, wi) = (dir(to, po), dir(ti, pi));
            let close = |ours: f32, theirs: f32| {
                if theirs == 0.0 {
                    ours == 0.0
                } else {
                    (ours / theirs - 1.0).abs() < 2e-3
                }
            };
            let (f, p) = (b.eval(wo, wi), b.pdf(wo, wi));
            assert!(
                close(f.r, red) && close(f.b, blue) && close(p, pdf),
                "{label}, ({to}, {po}) → ({ti}, {pi}): f {f:?} pdf {p} against Mitsuba's {red} {blue} {pdf}"
            );
        }
    }
}

/// A blend's sampled directions follow its mixture density (both sides of a `twosided` one),
/// and its delta samples carry their model's weight: a blend of a mirror with a black diffuse
/// reflects the mirror's share of the light on average.
#[test]
fn chi2_blend() {
    let b = mat(twosided(blend_gold(0.3)));
    for &(t, p) in &WO_ANGLES {
        run_chi2(&b, dir(t, p), Domain::Hemisphere, &format!("blend θo={t}"));
        run_chi2(
            &b,
            dir(180.0 - t, p),
            Domain::Sphere,
            &format!("blend below θo={t}"),
        );
    }
    let w = 0.35;
    let b = mat(blend(w, diffuse(0.0), conductor(0.0, 1.0)));
    let (mean, sigma) = albedo(&b, dir(30.0, 10.0), 20_000, 5);
    assert!(
        (mean - f64::from(w)).abs() < 4.0 * sigma + 1e-6,
        "{mean} ± {sigma}"
    );
}

/// `principled` against Mitsuba 3.9.1's own (`scalar_rgb`, `eval` with the cosine, the tangent
/// frame the axes): the three cases of [`principled_cases`] at eight direction pairs, from the
/// front, through the surface and from the back.
#[test]
fn principled_matches_mitsuba() {
    // (θo, φo, θi, φi, f·cos r, g, b).
    type Values = [(f32, f32, f32, f32, f32, f32, f32); 8];
    let values: [Values; 3] = [
        [
            (30.0, 0.0, 40.0, 180.0, 0.7790322, 0.3307022, 0.2410362),
            (10.0, 0.0, 70.0, 90.0, 0.06496628, 0.02473828, 0.01669268),
            (60.0, 10.0, 55.0, 200.0, 0.7240117, 0.3325281, 0.2542314),
            (80.0, 0.0, 75.0, 180.0, 6.267036, 4.741746, 4.436689),
            (0.0, 0.0, 30.0, 45.0, 0.2198447, 0.08762448, 0.06118043),
            (45.0, 0.0, 135.0, 180.0, 0.0, 0.0, 0.0),
            (150.0, 0.0, 20.0, 180.0, 0.0, 0.0, 0.0),
            (160.0, 30.0, 170.0, 220.0, 0.0, 0.0, 0.0),
        ],
        [
            (30.0, 0.0, 40.0, 180.0, 0.2334617, 0.2188331, 0.2042045),
            (10.0, 0.0, 70.0, 90.0, 0.02881919, 0.02242065, 0.0160221),
            (60.0, 10.0, 55.0, 200.0, 0.08268563, 0.07190587, 0.06112612),
            (80.0, 0.0, 75.0, 180.0, 19.70506, 19.70145, 19.69784),
            (0.0, 0.0, 30.0, 45.0, 0.07568631, 0.05914648, 0.04260663),
            (45.0, 0.0, 135.0, 180.0, 0.09218056, 0.08129561, 0.06870733),
            (150.0, 0.0, 20.0, 180.0, 0.05688107, 0.05016439, 0.04239665),
            (
                160.0, 30.0, 170.0, 220.0, 0.07175434, 0.07175434, 0.07175434,
            ),
        ],
        [
            (30.0, 0.0, 40.0, 180.0, 0.172142, 0.172142, 0.172142),
            (10.0, 0.0, 70.0, 90.0, 0.05690788, 0.05690788, 0.05690788),
            (60.0, 10.0, 55.0, 200.0, 0.1976922, 0.1976922, 0.1976922),
            (80.0, 0.0, 75.0, 180.0, 1.366188, 1.366188, 1.366188),
            (0.0, 0.0, 30.0, 45.0, 0.1504663, 0.1504663, 0.1504663),
            (45.0, 0.0, 135.0, 180.0, 0.0, 0.0, 0.0),
            (150.0, 0.0, 20.0, 180.0, 0.0, 0.0, 0.0),
            (160.0, 30.0, 170.0, 220.0, 0.0, 0.0, 0.0),
        ],
    ];
    for (k, (desc, values)) in principled_cases().into_iter().zip(values).enumerate() {
        let b = mat(desc);
        for (to, po, ti, pi, r, g, bl) in values {
            let f = b.eval(dir(to, po), dir(ti, pi));
            let expected = Rgb::new(r, g, bl);
            for ch in 0..3 {
                let (ours, theirs) = (f[ch], expected[ch]);
                assert!(
                    (ours - theirs).abs() <= 2e-3 * theirs.abs() + 1e-7,
                    "case {k}, ({to}, {po}) → ({ti}, {pi}): {f:?} against Mitsuba's {expected:?}"
                );
            }
        }
    }
}

/// The principled mixture's sampled directions follow its density, over the sphere where it
/// transmits (from both sides).
#[test]
fn chi2_principled() {
    for (k, desc) in principled_cases().into_iter().enumerate() {
        let b = mat(desc);
        for &(t, p) in &WO_ANGLES {
            run_chi2(
                &b,
                dir(t, p),
                Domain::Sphere,
                &format!("principled {k} θo={t}"),
            );
            if k == 1 {
                run_chi2(
                    &b,
                    dir(180.0 - t, p),
                    Domain::Sphere,
                    &format!("principled {k} below θo={t}"),
                );
            }
        }
    }
}

/// Mitsuba's bump-map shading: Estevez et al.'s shadowing at a closed-form point, 1 when off
/// or unperturbed; a perturbed normal that faces away from the viewer mirrored about the
/// unperturbed one; a bump normal turned to the geometric side.
#[test]
fn perturbed_shading_follows_mitsuba() {
    use crate::texture::Texture;
    use ircache_scene::PerturbedShading;
    let flat = |shading| {
        Perturbation::new(
            PerturbationMap::BumpMap(Texture::from_desc(&TextureDesc::Constant(Rgb::ONE)), 1.0),
            shading,
        )
    };
    let on = flat(PerturbedShading::default());
    let off = flat(PerturbedShading {
        shadowing: false,
        flip_invalid_normals: false,
    });
    let n = Vec3::Z;
    // n_p 30° from n: tan² = 1/3, α² = 1/24; light 60° from n: tan² = 3.
    let n_p = Vec3::new(0.5, 0.0, 0.75f32.sqrt());
    let wi = Vec3::new(0.0, 0.75f32.sqrt(), 0.5);
    let expect = 2.0 / (1.0 + (1.0f32 + 3.0 / 24.0).sqrt());
    assert!((on.shadowing(n, n_p, wi) - expect).abs() < 1e-6);
    assert_eq!(off.shadowing(n, n_p, wi), 1.0);
    assert_eq!(on.shadowing(n, n, wi), 1.0);
    // α² is capped at 1: a normal tilted 80° and light at the horizon's edge.
    let steep = Vec3::new(80f32.to_radians().sin(), 0.0, 80f32.to_radians().cos());
    let grazing = Vec3::new(0.0, 89f32.to_radians().sin(), 89f32.to_radians().cos());
    let t2 = 89f32.to_radians().tan().powi(2);
    assert!((on.shadowing(n, steep, grazing) - 2.0 / (1.0 + (1.0 + t2).sqrt())).abs() < 1e-4);

    // A normal map tilting the normal 60° towards +x, seen from far on −x: the normal faces
    // away from the viewer and is mirrored about n (towards −x) when flipping is on.
    let tilt = Vec3::new(60f32.to_radians().sin(), 0.0, 60f32.to_radians().cos());
    let colour = Rgb::new(0.5 * tilt.x + 0.5, 0.5, 0.5 * tilt.z + 0.5);
    let normal_map = |shading| {
        Perturbation::new(
            PerturbationMap::NormalMap(Texture::from_desc(&TextureDesc::Constant(colour))),
            shading,
        )
    };
    let viewer = Vec3::new(-80f32.to_radians().sin(), 0.0, 80f32.to_radians().cos());
    let (dpdu, dpdv) = (Vec3::X, Vec3::Y);
    let kept = normal_map(PerturbedShading {
        shadowing: true,
        flip_invalid_normals: false,
    })
    .normal(Vec2::ZERO, n, n, dpdu, dpdv, viewer);
    let flipped =
        normal_map(PerturbedShading::default()).normal(Vec2::ZERO, n, n, dpdu, dpdv, viewer);
    assert!((kept - tilt).length() < 1e-5, "{kept}");
    assert!(
        (flipped - Vec3::new(-tilt.x, 0.0, tilt.z)).length() < 1e-5,
        "{flipped}"
    );
    // The Lambertian share under uniform light, against a midpoint sum over the hemisphere of
    // n of S(ω) max(0, n_p·ω)/π (θ and φ on a grid, nothing in closed form): 1 untilted,
    // (1 + cos β)/2 without the shadowing function, below that with it.
    for tilt_deg in [0.0f32, 20.0, 45.0, 70.0] {
        let n_p = Vec3::new(
            tilt_deg.to_radians().sin(),
            0.0,
            tilt_deg.to_radians().cos(),
        );
        let (steps_t, steps_p) = (600, 1200);
        let (mut sum_on, mut sum_off) = (0.0f64, 0.0f64);
        for i in 0..steps_t {
            let theta = (i as f64 + 0.5) / steps_t as f64 * std::f64::consts::FRAC_PI_2;
            for j in 0..steps_p {
                let phi = (j as f64 + 0.5) / steps_p as f64 * std::f64::consts::TAU;
                let w = Vec3::new(
                    (theta.sin() * phi.cos()) as f32,
                    (theta.sin() * phi.sin()) as f32,
                    theta.cos() as f32,
                );
                let lobe = f64::from(n_p.dot(w).max(0.0));
                let area = theta.sin()
                    * (std::f64::consts::FRAC_PI_2 / steps_t as f64)
                    * (std::f64::consts::TAU / steps_p as f64);
                sum_on += f64::from(on.shadowing(n, n_p, w)) * lobe * area;
                sum_off += lobe * area;
            }
        }
        let (sum_on, sum_off) = (
            sum_on / std::f64::consts::PI,
            sum_off / std::f64::consts::PI,
        );
        let (share_on, share_off) = (on.lambertian_share(n, n_p), off.lambertian_share(n, n_p));
        assert!(
            (f64::from(share_on) - sum_on).abs() < 2e-3,
            "{tilt_deg}°: {share_on} against {sum_on}"
        );
        assert!(
            (f64::from(share_off) - sum_off).abs() < 2e-3,
            "{tilt_deg}°: {share_off} against {sum_off}"
        );
        let half = 0.5 * (1.0 + tilt_deg.to_radians().cos());
        assert!((share_off - half).abs() < 1e-6, "{share_off} {half}");
        assert!(share_on <= share_off + 1e-6);
    }
    // Seen from +x the same normal faces the viewer and stays.
    let front = Vec3::new(-viewer.x, 0.0, viewer.z);
    let stays = normal_map(PerturbedShading::default()).normal(Vec2::ZERO, n, n, dpdu, dpdv, front);
    assert!((stays - tilt).length() < 1e-5, "{stays}");
}

/// Radiance's `BSDF` with the Klems matrices of `scenes/radiance-bsdf/<file>`, turned by
/// `axis`, with Lambertian terms added.
fn klems(file: &str, axis: [f32; 2], added: [f32; 3]) -> Bsdf {
    let path = ircache_testing::project_scenes()
        .join("radiance-bsdf")
        .join(file);
    let data = Arc::new(ircache_scene::radiance::bsdf_xml::read(&path).unwrap());
    let mut b = mat(BsdfDesc::Klems {
        data,
        up: Vec3::Z,
        reflect_front: Rgb::splat(added[0]),
        reflect_back: Rgb::splat(added[1]),
        transmit: Rgb::splat(added[2]),
    });
    if let Bsdf::Single(Lobe::Klems(k)) = &mut b {
        k.axis = axis;
    }
    b
}

#[test]
fn chi2_and_weights_of_klems_matrices() {
    // The asymmetric matrix (full basis) from both sides, turned, with Lambertian terms; the
    // diffuser (quarter basis).
    let t = 0.4f32;
    let cases = [
        (
            "deflect",
            klems("deflect.xml", [t.cos(), t.sin()], [0.05, 0.0, 0.02]),
        ),
        ("diffuser", klems("diffuser.xml", [1.0, 0.0], [0.0; 3])),
    ];
    let mut rng = Rng::new(5, 6);
    for (label, b) in &cases {
        for (theta, phi) in [(33.0, 70.0), (118.0, 15.0)] {
            let wo = dir(theta, phi);
            // Fewer samples than the other models': each density averages 16 lookups.
            let test = ChiSquareTest {
                integration_tol: 1e-4,
                theta_bins: 10,
                phi_bins: 10,
                ..ChiSquareTest::sphere().with_samples(100_000)
            };
            let report = test.run(
                |u, u_lobe| b.sample(wo, u_lobe, u).map(|s| (s.wi, s.pdf)),
                |wi| b.pdf(wo, wi),
            );
            report.assert_ok(ALPHA, CHI2_TESTS, &format!("klems {label} θo={theta}"));
            for _ in 0..2000 {
                let Some(s) = b.sample(wo, rng.next_f32(), rng.next_2d()) else {
                    continue;
                };
                let (pdf, f) = (b.pdf(wo, s.wi), b.eval(wo, s.wi));
                assert!(
                    (pdf - s.pdf).abs() <= 1e-4 * pdf,
                    "{label}: {} vs {pdf}",
                    s.pdf
                );
                assert!(
                    (s.weight.g - f.g / pdf).abs() <= 1e-3 * (f.g / pdf),
                    "{label}: weight {:?}, eval/pdf {}",
                    s.weight,
                    f.g / pdf
                );
            }
        }
    }
}

#[test]
fn klems_photons_scatter_by_the_transposed_matrix() {
    // A photon arriving from wl leaves along wo weighted by f(wo, wl) |cos θo| / pdf (the
    // matrices are read with the view direction incident): the mean weight is
    // ∫ f(wo, wl) |cos θo| dwo, here by quadrature over the sphere with `eval`.
    let b = klems("deflect.xml", [0.6, 0.8], [0.05, 0.0, 0.0]);
    let mut rng = Rng::new(8, 9);
    for wl in [dir(20.0, 40.0), dir(130.0, 250.0)] {
        let mut quadrature = 0.0f64;
        let cells = upper_hemisphere_midpoints(|v| {
            for w in [v, Vec3::new(v.x, v.y, -v.z)] {
                quadrature += f64::from(b.eval(w, wl).g / wl.z.abs() * w.z.abs());
            }
        });
        quadrature *= 2.0 * f64::from(PI) / cells as f64;
        let n = 400_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            if let Some(s) = b.sample_adjoint(wl, rng.next_f32(), rng.next_2d()) {
                sum += f64::from(s.weight.g);
            }
        }
        let mean = sum / n as f64;
        assert!(
            (mean / quadrature - 1.0).abs() < 0.01,
            "from {wl}: photons keep {mean}, the transposed matrix {quadrature}"
        );
        // Not what sampling the view-incident matrix would give.
        let forward = albedo(&b, wl, n, 3).0;
        assert!(
            (forward / quadrature - 1.0).abs() > 0.05,
            "{forward} vs {quadrature}"
        );
    }
}

#[test]
fn chi2_and_closed_forms_of_radiance_anisotropic_ward() {
    // plastic2 and metal2: agaussamp's half vectors against the density they claim, from both
    // sides and turned; trans2's transmission likewise; the lobe with equal roughnesses is the
    // isotropic one; and turning the axis by 90° swaps the roughnesses.
    let t = 0.7f32;
    let mut turned_trans2 = mat(trans2(0.8, 0.05, 0.3));
    if let Bsdf::TwoSided {
        front: Lobe::Ward(f),
        back: Lobe::Ward(k),
    } = &mut turned_trans2
    {
        f.axis = [t.cos(), t.sin()];
        k.axis = [t.cos(), t.sin()];
    }
    for (label, b) in [
        (
            "metal2",
            ward2(0.8, 0.9, 0.04, 0.25, true, [t.cos(), t.sin()]),
        ),
        ("plastic2", ward2(0.5, 0.1, 0.3, 0.06, false, [1.0, 0.0])),
        ("trans2", turned_trans2),
    ] {
        for (theta, phi) in [(20.0, 30.0), (65.0, 250.0), (150.0, 100.0)] {
            let wo = dir(theta, phi);
            let domain = Domain::Sphere;
            run_chi2(&b, wo, domain, &format!("{label} θo={theta}"));
        }
    }
    let iso = mat(ward(0.8, 0.9, 0.1, true));
    let equal = ward2(0.8, 0.9, 0.1, 0.1 + 1e-7, true, [0.3, 0.954]);
    let a = ward2(0.8, 0.9, 0.04, 0.25, true, [1.0, 0.0]);
    let b = ward2(0.8, 0.9, 0.25, 0.04, true, [0.0, 1.0]);
    let mut rng = Rng::new(3, 4);
    for _ in 0..500 {
        let wo = ircache_math::sampling::square_to_uniform_hemisphere(rng.next_2d());
        let wi = ircache_math::sampling::square_to_uniform_hemisphere(rng.next_2d());
        // The two formulas round differently in f32 (the isotropic one takes the tangent from
        // h·h − (h·n)², which cancels near the peak).
        let (x, y) = (iso.eval(wo, wi).g, equal.eval(wo, wi).g);
        assert!((x - y).abs() <= 2e-3 * x.max(1e-3), "{x} vs {y}");
        let (x, y) = (a.eval(wo, wi).g, b.eval(wo, wi).g);
        assert!((x - y).abs() <= 1e-4 * x.max(1e-3), "{x} vs {y}");
        let (x, y) = (a.pdf(wo, wi), b.pdf(wo, wi));
        assert!((x - y).abs() <= 1e-4 * x.max(1e-3), "{x} vs {y}");
    }
}

#[test]
fn radiance_brtdfunc_parts() {
    // BRTDfunc's Lambertian parts sampled as they claim (χ², both sides); its deltas chosen
    // by luminance with their exact weights; what it keeps of a direction's light is
    // R + T + the Lambertian albedos of that side.
    let b = Bsdf::Single(Lobe::Brtd(Brtd {
        reflect: Rgb::new(0.3, 0.2, 0.1),
        transmit: Rgb::new(0.4, 0.5, 0.6),
        diffuse_front: Rgb::splat(0.05),
        diffuse_back: Rgb::splat(0.1),
        diffuse_transmit: Rgb::new(0.02, 0.03, 0.04),
    }));
    for theta in [30.0, 140.0] {
        let wo = dir(theta, 60.0);
        let test = ChiSquareTest::sphere().with_samples(200_000);
        let report = test.run(
            |u, u_lobe| {
                let s = b.sample(wo, u_lobe, u)?;
                (!s.delta).then_some((s.wi, s.pdf))
            },
            |wi| b.pdf(wo, wi),
        );
        report.assert_ok(ALPHA, CHI2_TESTS, &format!("BRTDfunc θo={theta}"));
        let (m, s) = albedo(&b, wo, 200_000, 9);
        let diffuse = if theta < 90.0 { 0.05 } else { 0.1 };
        let expected = 0.3 + 0.4 + diffuse + 0.02;
        assert!(
            (m - expected).abs() < 4.0 * s + 1e-3,
            "θo={theta}: {m} ± {s} vs {expected}"
        );
    }
    let wo = dir(40.0, 10.0);
    let mut rng = Rng::new(2, 3);
    for _ in 0..2000 {
        let Some(s) = b.sample(wo, rng.next_f32(), rng.next_2d()) else {
            continue;
        };
        if s.delta {
            let straight = (s.wi + wo).length() < 1e-6;
            let mirror = (s.wi - Vec3::new(-wo.x, -wo.y, wo.z)).length() < 1e-6;
            assert!(straight || mirror, "{s:?}");
            let value = if straight {
                Rgb::new(0.4, 0.5, 0.6)
            } else {
                Rgb::new(0.3, 0.2, 0.1)
            };
            assert!(
                (s.weight * s.pdf - value).max_channel().abs() < 1e-5,
                "{s:?}"
            );
        }
    }
}
