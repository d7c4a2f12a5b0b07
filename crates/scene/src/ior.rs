//! Named indices of refraction, as Mitsuba 3 accepts them in `int_ior` / `ext_ior` (dielectrics)
//! and `material` (conductors).
//!
//! The dielectric table is Mitsuba 3's `ior.h` (values at ~589 nm, mostly from Hecht, *Optics*).
//! Mitsuba 3 reads a conductor's spectral complex IOR from `data/ior/<name>.{eta,k}.spd` and, in
//! its RGB variants, integrates it to linear sRGB. The RGB values here are the widely used
//! integration of the same measured spectra published with the Tungsten renderer; they can differ
//! from Mitsuba's own conversion in the third decimal place.

use ircache_math::Rgb;

/// Dielectric IORs by name (lower case), as in Mitsuba 3.
pub const DIELECTRIC_IORS: &[(&str, f32)] = &[
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// Looks up a dielectric IOR by name, case-insensitively (Mitsuba lower-cases the name).
#[must_use]
pub fn dielectric_ior(name: &str) -> Option<f32> {
    let lower = name.trim().to_ascii_lowercase();
    DIELECTRIC_IORS
        .iter()
        .find(|(n, _)| *n == lower)
        .map(|&(_, v)| v)
}

/// Conductor complex IORs by Mitsuba material name: `(name, eta, k)` in linear RGB.
#[allow(clippy::excessive_precision)] // the published values, digit for digit
pub const CONDUCTOR_IORS: &[(&str, [f32; 3], [f32; 3])] = &[
    (
        "a-C",
        [2.944_099_9, 2.227_150_3, 1.968_166_9],
        [0.887_432_9, 0.799_321_6, 0.815_286_3],
    ),
    (
        "Ag",
        [0.155_264_65, 0.116_723_3, 0.138_380_7],
        [4.828_343_3, 3.122_246, 2.146_950_4],
    ),
    (
        "Al",
        [1.657_46, 0.880_369, 0.521_228_7],
        [9.223_869, 6.269_523, 4.837_001],
    ),
    (
        "Au",
        [0.143_118_96, 0.374_957_04, 1.442_478_6],
        [3.983_160_4, 2.385_720_7, 1.603_215_3],
    ),
    (
        "Be",
        [4.185_059, 3.185_060_5, 2.784_091_3],
        [3.835_439_9, 3.010_126, 2.869_008_8],
    ),
    (
        "Cr",
        [4.369_683, 2.916_702_5, 1.654_700_5],
        [5.206_434, 4.231_364_5, 3.754_946_7],
    ),
    (
        "Cu",
        [0.200_437_7, 0.924_033_4, 1.102_212],
        [3.912_948_6, 2.452_847_7, 2.142_188],
    ),
    (
        "Cu2O",
        [3.549_283_3, 2.952_062_3, 2.736_920_2],
        [0.113_217_93, 0.194_665_97, 0.600_168_1],
    ),
    (
        "CuO",
        [3.245_382_3, 2.449_629_5, 2.197_411_5],
        [0.520_273_96, 0.570_737_3, 0.717_225_1],
    ),
    (
        "d-C",
        [2.711_252_5, 2.318_581_3, 2.228_856_5],
        [0.0, 0.0, 0.0],
    ),
    (
        "Hg",
        [2.398_931_5, 1.440_025_5, 0.909_551_2],
        [6.327_627, 4.371_941_4, 3.421_79],
    ),
    (
        "HgTe",
        [4.779_527, 3.230_998_5, 2.660_025_2],
        [1.631_982_7, 1.580_819, 1.729_575_4],
    ),
    (
        "Ir",
        [3.086_41, 2.082_193_8, 1.617_886_7],
        [5.592_151, 4.067_175_7, 3.267_261],
    ),
    (
        "K",
        [0.064_049_31, 0.046_410_06, 0.038_184_2],
        [2.104_215_6, 1.348_936_4, 0.913_211_4],
    ),
    (
        "Li",
        [0.265_787_2, 0.195_610_24, 0.220_919_85],
        [3.540_174_2, 2.311_130_5, 1.668_593],
    ),
    (
        "MgO",
        [2.089_588_6, 1.650_722_5, 1.594_876],
        [0.0, 0.0, 0.0],
    ),
    (
        "Mo",
        [4.483_701, 3.525_457_9, 2.776_077],
        [4.111_130_7, 3.420_871_7, 3.150_603],
    ),
    (
        "Na",
        [0.060_266_53, 0.056_141_24, 0.061_990_95],
        [3.179_290_6, 2.112_48, 1.579_094],
    ),
    (
        "Nb",
        [3.420_135_5, 2.790_192, 2.395_585_7],
        [3.441_381_7, 2.737_643_7, 2.579_913_3],
    ),
    (
        "Ni",
        [2.367_275_2, 1.663_358_3, 1.467_055_4],
        [4.498_833, 3.050_164_4, 2.345_427_5],
    ),
    (
        "Rh",
        [2.585_795_4, 1.860_186_6, 1.554_428],
        [6.782_293, 4.702_95, 3.976_089_2],
    ),
    (
        "Se",
        [4.059_261, 2.842_694_8, 2.820_758_3],
        [0.754_379_2, 0.638_515, 0.521_587_2],
    ),
    (
        "SiC",
        [3.172_345, 2.525_967_8, 2.479_362_4],
        [0.0, 0.0, 0.000_010_015],
    ),
    (
        "SnTe",
        [4.525_186_5, 1.981_152_6, 1.281_682],
        [0.0, 0.0, 0.0],
    ),
    (
        "Ta",
        [2.062_584_6, 2.393_091_5, 2.628_068_4],
        [2.408_046_7, 1.741_370_6, 1.947_037_7],
    ),
    (
        "Te",
        [7.390_84, 4.482_103, 2.637_070_8],
        [3.256_141_2, 3.527_390_7, 3.292_168_4],
    ),
    (
        "ThF4",
        [1.830_718_7, 1.442_227_4, 1.387_648_8],
        [0.0, 0.0, 0.0],
    ),
    (
        "TiC",
        [3.700_467_3, 2.837_435_7, 2.582_303],
        [3.265_690_6, 2.351_558_7, 2.172_785_8],
    ),
    (
        "TiN",
        [1.648_469_2, 1.150_448_3, 1.379_779_5],
        [3.368_459_7, 1.943_488_9, 1.102_012_3],
    ),
    (
        "TiO2",
        [3.456_620_2, 2.801_707_7, 2.905_148_5],
        [0.000_102_666_2, 0.0, 0.000_635_690_2],
    ),
    (
        "VC",
        [3.657_566_5, 2.752_73, 2.532_681_5],
        [3.068_351_7, 2.198_668_7, 1.963_181_6],
    ),
    (
        "VN",
        [2.865_601_3, 2.119_181_9, 1.940_076_7],
        [3.032_326_4, 2.056_107_5, 1.616_293],
    ),
    (
        "V",
        [4.277_512_6, 3.513_153_8, 2.761_125_8],
        [3.491_184_5, 2.889_358, 3.111_696_5],
    ),
    (
        "W",
        [4.370_703, 3.300_297_2, 2.998_266_6],
        [3.500_678, 2.604_865_3, 2.273_193],
    ),
];

/// Looks up a conductor's RGB `(eta, k)` by Mitsuba material name. Names are matched exactly
/// first, then case-insensitively; Mitsuba's `_palik` variants map to the same entry. `"none"`
/// is Mitsuba's default, a perfect mirror: `eta = 0`, `k = 1`.
#[must_use]
pub fn conductor_ior(name: &str) -> Option<(Rgb, Rgb)> {
    let name = name.trim();
    if name == "none" {
        return Some((Rgb::splat(0.0), Rgb::splat(1.0)));
    }
    let base = name.strip_suffix("_palik").unwrap_or(name);
    CONDUCTOR_IORS
        .iter()
        .find(|(n, _, _)| *n == base)
        .or_else(|| {
            CONDUCTOR_IORS
                .iter()
                .find(|(n, _, _)| n.eq_ignore_ascii_case(base))
        })
        .map(|&(_, eta, k)| (Rgb::from_array(eta), Rgb::from_array(k)))
}

/// The conductor names accepted by [`conductor_ior`], for error messages.
#[must_use]
pub fn conductor_names() -> Vec<&'static str> {
    let mut v: Vec<&str> = CONDUCTOR_IORS.iter().map(|(n, _, _)| *n).collect();
    v.push("none");
    v
}

/// The dielectric names accepted by [`dielectric_ior`], for error messages.
#[must_use]
pub fn dielectric_names() -> Vec<&'static str> {
    DIELECTRIC_IORS.iter().map(|(n, _)| *n).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_lookup() {
        assert_eq!(dielectric_ior("BK7"), Some(1.5046));
        assert_eq!(dielectric_ior("acrylic glass"), Some(1.49));
        assert_eq!(dielectric_ior("air"), Some(1.000277));
        assert_eq!(dielectric_ior("unobtainium"), None);
    }

    #[test]
    fn conductor_lookup() {
        let (eta, k) = conductor_ior("Cu").unwrap();
        assert!((eta.r - 0.200438).abs() < 1e-5 && (k.b - 2.14219).abs() < 1e-5);
        assert!(conductor_ior("Au_palik").is_some());
        assert!(conductor_ior("al").is_some());
        assert_eq!(
            conductor_ior("none"),
            Some((Rgb::splat(0.0), Rgb::splat(1.0)))
        );
        assert_eq!(conductor_ior("Xx"), None);
    }
}
