//! The CIE 1931 2° standard observer's colour-matching functions and the CIE D65 illuminant at
//! 5 nm from 360 to 830 nm (95 samples; CIE 018:2019 / ISO 11664-1 and ISO 11664-2, the values
//! as the `colour-science` package tabulates them), and the conversion of a spectrum given as
//! wavelength–value pairs to linear sRGB as Mitsuba 3's RGB variants do it
//! (`spectrum_list_to_srgb`): 1000 wavelengths over [360, 830] nm, the spectrum linearly
//! interpolated between its pairs and zero outside them, the tables linearly interpolated,
//! reflectances weighted by D65, Y normalised so that a flat unit spectrum has Y = 1, then the
//! XYZ → sRGB matrix.

use ircache_math::Rgb;

/// First tabulated wavelength (nm).
const FIRST: f64 = 360.0;
/// Last tabulated wavelength (nm).
const LAST: f64 = 830.0;
/// Samples of the tables (5 nm apart).
const SAMPLES: usize = 95;

/// x̄, ȳ, z̄ at 360, 365, …, 830 nm.
#[rustfmt::skip]
const CMF_X: [f64; SAMPLES] = [
    0.0001299, 0.0002321, 0.0004149, 0.0007416, 0.001368, 0.002236, 0.004243, 0.00765,
    0.01431, 0.02319, 0.04351, 0.07763, 0.13438, 0.21477, 0.2839, 0.3285,
    0.34828, 0.34806, 0.3362, 0.3187, 0.2908, 0.2511, 0.19536, 0.1421,
    0.09564, 0.05795001, 0.03201, 0.0147, 0.0049, 0.0024, 0.0093, 0.0291,
    0.06327, 0.1096, 0.1655, 0.2257499, 0.2904, 0.3597, 0.4334499, 0.5120501,
    0.5945, 0.6784, 0.7621, 0.8425, 0.9163, 0.9786, 1.0263, 1.0567,
    1.0622, 1.0456, 1.0026, 0.9384, 0.8544499, 0.7514, 0.6424, 0.5419,
    0.4479, 0.3608, 0.2835, 0.2187, 0.1649, 0.1212, 0.0874, 0.0636,
    0.04677, 0.0329, 0.0227, 0.01584, 0.01135916, 0.008110916, 0.005790346, 0.004109457,
    0.002899327, 0.00204919, 0.001439971, 0.0009999493, 0.0006900786, 0.0004760213, 0.0003323011, 0.0002348261,
    0.0001661505, 0.000117413, 8.307527e-5, 5.870652e-5, 4.150994e-5, 2.935326e-5, 2.067383e-5, 1.455977e-5,
    1.025398e-5, 7.221456e-6, 5.085868e-6, 3.581652e-6, 2.522525e-6, 1.776509e-6, 1.251141e-6,
];
#[rustfmt::skip]
const CMF_Y: [f64; SAMPLES] = [
    3.917e-6, 6.965e-6, 1.239e-5, 2.202e-5, 3.9e-5, 6.4e-5, 0.00012, 0.000217,
    0.000396, 0.00064, 0.00121, 0.00218, 0.004, 0.0073, 0.0116, 0.01684,
    0.023, 0.0298, 0.038, 0.048, 0.06, 0.0739, 0.09098, 0.1126,
    0.13902, 0.1693, 0.20802, 0.2586, 0.323, 0.4073, 0.503, 0.6082,
    0.71, 0.7932, 0.862, 0.9148501, 0.954, 0.9803, 0.9949501, 1.0,
    0.995, 0.9786, 0.952, 0.9154, 0.87, 0.8163, 0.757, 0.6949,
    0.631, 0.5668, 0.503, 0.4412, 0.381, 0.321, 0.265, 0.217,
    0.175, 0.1382, 0.107, 0.0816, 0.061, 0.04458, 0.032, 0.0232,
    0.017, 0.01192, 0.00821, 0.005723, 0.004102, 0.002929, 0.002091, 0.001484,
    0.001047, 0.00074, 0.00052, 0.0003611, 0.0002492, 0.0001719, 0.00012, 8.48e-5,
    6e-5, 4.24e-5, 3e-5, 2.12e-5, 1.499e-5, 1.06e-5, 7.4657e-6, 5.2578e-6,
    3.7029e-6, 2.6078e-6, 1.8366e-6, 1.2934e-6, 9.1093e-7, 6.4153e-7, 4.5181e-7,
];
#[rustfmt::skip]
const CMF_Z: [f64; SAMPLES] = [
    0.0006061, 0.001086, 0.001946, 0.003486, 0.006450001, 0.01054999, 0.02005001, 0.03621,
    0.06785001, 0.1102, 0.2074, 0.3713, 0.6456, 1.03905, 1.3856, 1.62296,
    1.74706, 1.7826, 1.77211, 1.7441, 1.6692, 1.5281, 1.28764, 1.0419,
    0.8129501, 0.6162, 0.46518, 0.3533, 0.272, 0.2123, 0.1582, 0.1117,
    0.07824999, 0.05725001, 0.04216, 0.02984, 0.0203, 0.0134, 0.008749999, 0.005749999,
    0.0039, 0.002749999, 0.0021, 0.0018, 0.001650001, 0.0014, 0.0011, 0.001,
    0.0008, 0.0006, 0.00034, 0.00024, 0.00019, 0.0001, 4.999999e-5, 3e-5,
    2e-5, 1e-5, 2.117582e-22, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
];
/// D65's relative spectral power at the same wavelengths.
#[rustfmt::skip]
const D65: [f64; SAMPLES] = [
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015,
    82.7549, 87.1204, 91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736,
    104.865, 110.936, 117.008, 117.41, 117.812, 116.336, 114.861, 115.392,
    115.923, 112.367, 108.811, 109.082, 109.354, 108.578, 107.802, 106.296,
    104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023,
    100.0, 98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459,
    90.0062, 89.8026, 89.5991, 88.6489, 87.6987, 85.4936, 83.2886, 83.4939,
    83.6992, 81.863, 80.0268, 80.1207, 80.2146, 81.2462, 82.2778, 80.281,
    78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.979, 74.349, 67.9765,
    61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398, 63.5927, 55.0054,
    46.4182, 56.6118, 66.8054, 65.0941, 63.3828, 63.3828, 63.3828, 63.3828,
    63.3828, 63.3828, 63.3828, 63.3828, 63.3828, 63.3828, 63.3828,
];

/// Mitsuba 3's normalisation of ȳ (`MI_CIE_Y_NORMALIZATION`): ∫ȳ over the tables by the
/// same 1000-point sum (the tables above give 106.75020).
const Y_NORMALIZATION: f64 = 1.0 / 106.750_259_399_414_06;
/// Mitsuba 3's normalisation of D65 (`MI_CIE_D65_NORMALIZATION`).
const D65_NORMALIZATION: f64 = 1.0 / 98.997_417_518_762_55;

/// CIE XYZ to linear sRGB (Mitsuba 3's `xyz_to_srgb`, D65 white).
const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [3.240_479, -1.537_15, -0.498_535],
    [-0.969_256, 1.875_991, 0.041_556],
    [0.055_648, -0.204_043, 1.057_311],
];

fn xyz_to_srgb(xyz: [f64; 3]) -> [f64; 3] {
    XYZ_TO_SRGB.map(|row| row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2])
}

/// The linear sRGB colour of a unit equal-energy spectrum, `xyz_to_srgb(1, 1, 1)`: how Mitsuba
/// 3's RGB variants read a constant `<spectrum>` as an emitter's radiance (sRGB's white is D65,
/// so equal energy is slightly red).
pub(crate) fn equal_energy_srgb() -> Rgb {
    let [r, g, b] = xyz_to_srgb([1.0; 3]);
    Rgb::new(r as f32, g as f32, b as f32)
}

/// A table linearly interpolated at `w` nm (zero outside [360, 830]).
fn table(t: &[f64; SAMPLES], w: f64) -> f64 {
    if !(FIRST..=LAST).contains(&w) {
        return 0.0;
    }
    let x = (w - FIRST) * (SAMPLES - 1) as f64 / (LAST - FIRST);
    let i = (x as usize).min(SAMPLES - 2);
    let f = x - i as f64;
    t[i] * (1.0 - f) + t[i + 1] * f
}

/// How a spectrum's colour is read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum SpectrumUse {
    /// A reflectance or another ratio: weighted by D65 (a flat unit spectrum is white).
    Ratio,
    /// An emitter's radiance, irradiance or intensity: unweighted.
    Emission,
}

/// The linear sRGB colour of the spectrum through `pairs` (wavelengths in nm, increasing),
/// with negative channels raised to zero, as Mitsuba 3's RGB variants read it, and whether a
/// channel was raised (Mitsuba warns; the caller says so).
pub(crate) fn spectrum_to_srgb(pairs: &[(f64, f64)], usage: SpectrumUse) -> (Rgb, bool) {
    debug_assert!(pairs.len() >= 2, "the parser keeps at least two pairs");
    const STEPS: usize = 1000;
    let (first, last) = (pairs[0].0, pairs[pairs.len() - 1].0);
    let mut xyz = [0.0f64; 3];
    for i in 0..STEPS {
        let w = FIRST + (i as f64 / (STEPS - 1) as f64) * (LAST - FIRST);
        if w < first || w > last {
            continue;
        }
        // The last pair whose wavelength is ≤ w, and the next (wavelengths increase).
        let k = pairs
            .partition_point(|&(wk, _)| wk <= w)
            .clamp(1, pairs.len() - 1)
            - 1;
        let ((w0, v0), (w1, v1)) = (pairs[k], pairs[k + 1]);
        let v = ((w - w1) * v0 + (w0 - w) * v1) / (w0 - w1);
        let weight = match usage {
            SpectrumUse::Ratio => table(&D65, w) * D65_NORMALIZATION,
            SpectrumUse::Emission => 1.0,
        };
        for (c, t) in xyz.iter_mut().zip([&CMF_X, &CMF_Y, &CMF_Z]) {
            *c += table(t, w) * v * weight;
        }
    }
    let scale = (LAST - FIRST) * Y_NORMALIZATION / STEPS as f64;
    let rgb = xyz_to_srgb(xyz.map(|c| c * scale));
    let raised = rgb.iter().any(|&c| c < 0.0);
    let [r, g, b] = rgb.map(|c| c.max(0.0) as f32);
    (Rgb::new(r, g, b), raised)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spectra_convert_as_mitsuba_converts_them() {
        // Values Mitsuba 3.9.1 (llvm_ad_rgb) itself gives for these spectra: an area
        // emitter's radiance and a diffuse reflectance (eval × π at normal incidence).
        let close = |a: Rgb, b: [f32; 3]| {
            a.to_array()
                .iter()
                .zip(b)
                .all(|(x, y)| (x - y).abs() < 2e-4 * y.max(0.1))
        };
        let (e, _) = spectrum_to_srgb(
            &[(400.0, 1.0), (500.0, 2.0), (600.0, 1.0), (700.0, 0.5)],
            SpectrumUse::Emission,
        );
        assert!(close(e, [0.841_016, 1.552_85, 1.391_45]), "{e:?}");
        let (r, _) = spectrum_to_srgb(
            &[(400.0, 0.2), (500.0, 0.5), (600.0, 0.6), (700.0, 0.7)],
            SpectrumUse::Ratio,
        );
        assert!(close(r, [0.633_695, 0.550_547, 0.335_712]), "{r:?}");
    }
}
