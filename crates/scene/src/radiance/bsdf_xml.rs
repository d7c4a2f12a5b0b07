//! Reads the Klems BSDF matrices of an LBNL XML file (WINDOW 6, `genBSDF`, `wrapBSDF`), as
//! Radiance's `bsdf_m.c` (`SDloadMtx`) does: the first optical layer, its angle bases, and the
//! `Visible` (CIE Y) data of each direction, coloured by `CIE-X` and `CIE-Z` data where the file
//! has them. Tensor-tree files are refused.

use crate::klems::{AngleBasis, KlemsBsdf, KlemsComponent, KlemsMatrix};
use ircache_math::Rgb;
use roxmltree::Node;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

/// CIE XYZ to Radiance's RGB (its primaries (0.640, 0.330), (0.290, 0.600), (0.150, 0.060),
/// equal-energy white; `color.h`).
fn xyz_to_radiance_rgb(xyz: [f64; 3]) -> [f64; 3] {
    // The primaries' XYZ columns scaled so that (1, 1, 1) is white (X = Y = Z), inverted.
    let prim = [[0.640, 0.330], [0.290, 0.600], [0.150, 0.060]];
    let col = |[x, y]: [f64; 2]| [x / y, 1.0, (1.0 - x - y) / y];
    let m = [col(prim[0]), col(prim[1]), col(prim[2])]; // columns
    let a = ircache_math::DMat3::from_cols(m[0].into(), m[1].into(), m[2].into());
    let s = a.inverse() * ircache_math::DVec3::ONE;
    let to_xyz = ircache_math::DMat3::from_cols(a.x_axis * s.x, a.y_axis * s.y, a.z_axis * s.z);
    (to_xyz.inverse() * ircache_math::DVec3::from(xyz)).to_array()
}

/// One channel of a matrix as read: its incident and outgoing bases and its values.
type Channel = (Arc<AngleBasis>, Arc<AngleBasis>, Vec<f32>);

/// The first child element of `n` named `name`.
fn child<'a, 'i>(n: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    n.children()
        .find(|c| c.is_element() && c.tag_name().name() == name)
}

/// The trimmed text of `n`'s child element `name`.
fn text_of(n: Node<'_, '_>, name: &str) -> Option<String> {
    child(n, name).map(|c| c.text().unwrap_or("").trim().to_string())
}

/// Reads the Klems BSDF at `path`; errors are messages for the caller to place.
pub fn read(path: &Path) -> Result<KlemsBsdf, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read it: {e}"))?;
    parse(&text, path)
}

/// The Klems BSDF in the XML `text` of the file at `path`.
pub fn parse(text: &str, path: &Path) -> Result<KlemsBsdf, String> {
    let doc = roxmltree::Document::parse(text).map_err(|e| format!("not XML: {e}"))?;
    let root = doc.root_element();
    let layer = child(root, "Optical")
        .and_then(|o| child(o, "Layer"))
        .ok_or("no <Optical><Layer> element")?;
    let definition = child(layer, "DataDefinition").ok_or("no <DataDefinition> in its layer")?;
    let structure = text_of(definition, "IncidentDataStructure")
        .ok_or("no <IncidentDataStructure> in its <DataDefinition>")?;
    let incident_rows = match structure.to_ascii_lowercase().as_str() {
        "rows" => true,
        "columns" => false,
        s if s.starts_with("tensortree") => {
            return Err(format!(
                "its data is a tensor tree ({structure}); ircache reads Klems matrices only"
            ))
        }
        _ => return Err(format!("unknown <IncidentDataStructure> \"{structure}\"")),
    };
    // The bases it defines, then the standard ones by name.
    let mut bases: HashMap<String, Arc<AngleBasis>> = HashMap::new();
    for ab in definition
        .children()
        .filter(|c| c.has_tag_name("AngleBasis"))
    {
        let name = text_of(ab, "AngleBasisName").ok_or("an <AngleBasis> without a name")?;
        let (mut lower, mut phis) = (Vec::new(), Vec::new());
        let mut upper_prev: Option<f64> = None;
        for block in ab.children().filter(|c| c.has_tag_name("AngleBasisBlock")) {
            let number = |n: Option<Node<'_, '_>>, what: &str| -> Result<f64, String> {
                n.and_then(|n| n.text())
                    .and_then(|t| t.trim().parse::<f64>().ok())
                    .ok_or(format!(
                        "basis \"{name}\": a block without a numeric <{what}>"
                    ))
            };
            let bounds = child(block, "ThetaBounds");
            let lo = number(bounds.and_then(|b| child(b, "LowerTheta")), "LowerTheta")?;
            let hi = number(bounds.and_then(|b| child(b, "UpperTheta")), "UpperTheta")?;
            if let Some(prev) = upper_prev {
                if (lo - prev).abs() > 1e-6 * prev.abs().max(1.0) {
                    return Err(format!(
                        "basis \"{name}\": a ring starts at {lo}° where the one before ended \
                         at {prev}°"
                    ));
                }
            }
            upper_prev = Some(hi);
            let n = number(child(block, "nPhis"), "nPhis")?;
            lower.push(lo);
            phis.push(n as u32);
        }
        if upper_prev.is_some_and(|u| (u - 90.0).abs() > 1e-6) {
            return Err(format!("basis \"{name}\": its last ring ends before 90°"));
        }
        let basis = AngleBasis::new(&name, &lower, &phis).ok_or(format!(
            "basis \"{name}\": rings must start at 0°, increase, have one patch at the pole \
             and at least one elsewhere"
        ))?;
        bases.insert(name.to_ascii_lowercase(), Arc::new(basis));
    }
    let mut basis = |name: &str| -> Result<Arc<AngleBasis>, String> {
        let key = name.to_ascii_lowercase();
        if let Some(b) = bases.get(&key) {
            return Ok(b.clone());
        }
        let b = Arc::new(
            AngleBasis::standard(name).ok_or(format!("undefined angle basis \"{name}\""))?,
        );
        bases.insert(key, b.clone());
        Ok(b)
    };
    // Per component, the Y, X and Z matrices (values in `mBSDF_value` order).
    let mut channels: [[Option<Channel>; 3]; 4] = Default::default();
    for wd in layer
        .children()
        .filter(|c| c.has_tag_name("WavelengthData"))
    {
        let wavelength = text_of(wd, "Wavelength").unwrap_or_default();
        let channel = match wavelength.to_ascii_lowercase().as_str() {
            "visible" => 0,
            "cie-x" => 1,
            "cie-z" => 2,
            _ => continue, // Solar and other bands: not light (as bsdf_m.c).
        };
        for block in wd
            .children()
            .filter(|c| c.has_tag_name("WavelengthDataBlock"))
        {
            let line = doc.text_pos_at(block.range().start).row;
            let direction = format!(
                "line {line}: {}",
                text_of(block, "WavelengthDataDirection").unwrap_or_default()
            );
            // WINDOW's front is Radiance's back (bsdf_m.c).
            let component = match text_of(block, "WavelengthDataDirection")
                .unwrap_or_default()
                .to_ascii_lowercase()
                .as_str()
            {
                "transmission front" => KlemsComponent::TransmitBack,
                "transmission back" => KlemsComponent::TransmitFront,
                "reflection front" => KlemsComponent::ReflectBack,
                "reflection back" => KlemsComponent::ReflectFront,
                _ => {
                    return Err(format!(
                        "{direction}: unknown <WavelengthDataDirection> (expected \
                         Transmission or Reflection, Front or Back)"
                    ))
                }
            };
            let incident = basis(
                &text_of(block, "ColumnAngleBasis")
                    .ok_or(format!("{direction}: no <ColumnAngleBasis>"))?,
            )?;
            let outgoing = basis(
                &text_of(block, "RowAngleBasis")
                    .ok_or(format!("{direction}: no <RowAngleBasis>"))?,
            )?;
            let data = text_of(block, "ScatteringData")
                .ok_or(format!("{direction}: no <ScatteringData>"))?;
            let (ni, no) = (incident.len(), outgoing.len());
            // Read first, so that what is allocated is bounded by the file's size.
            let read = data
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter(|w| !w.is_empty())
                .map(|word| match word.parse::<f32>() {
                    Ok(v) if v.is_finite() => Ok(v),
                    _ => Err(format!(
                        "{direction} ({wavelength}): \"{word}\" is not a finite number"
                    )),
                })
                .collect::<Result<Vec<f32>, String>>()?;
            if Some(read.len()) != ni.checked_mul(no) {
                return Err(format!(
                    "{direction} ({wavelength}): {} values where a {no} × {ni} matrix has {}",
                    read.len(),
                    ni as u128 * no as u128
                ));
            }
            // Negative values are taken as zero (bsdf_m.c).
            let mut values = vec![0f32; read.len()];
            for (k, v) in read.into_iter().enumerate() {
                let index = if incident_rows {
                    (k % no) * ni + k / no
                } else {
                    k
                };
                values[index] = v.max(0.0);
            }
            channels[component as usize][channel] = Some((incident, outgoing, values));
        }
    }
    let mut components: [Option<KlemsMatrix>; 4] = Default::default();
    for (c, [y, x, z]) in channels.into_iter().enumerate() {
        let Some((incident, outgoing, y)) = y else {
            continue;
        };
        let same = |m: &Option<Channel>| {
            m.as_ref()
                .filter(|(i, o, _)| i.len() == incident.len() && o.len() == outgoing.len())
                .map(|(_, _, v)| v.clone())
        };
        let values = match (same(&x), same(&z)) {
            (Some(x), Some(z)) => (0..y.len())
                .map(|k| {
                    let [r, g, b] = xyz_to_radiance_rgb([x[k], y[k], z[k]].map(f64::from));
                    Rgb::new(r.max(0.0) as f32, g.max(0.0) as f32, b.max(0.0) as f32)
                })
                .collect(),
            _ => y.iter().map(|&v| Rgb::splat(v)).collect(),
        };
        components[c] = Some(KlemsMatrix {
            incident,
            outgoing,
            values,
        });
    }
    if components.iter().all(Option::is_none) {
        return Err("no Visible (CIE Y) scattering data in its first layer".into());
    }
    Ok(KlemsBsdf {
        source: path.to_path_buf(),
        components,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn white_stays_white() {
        let [r, g, b] = xyz_to_radiance_rgb([1.0, 1.0, 1.0]);
        assert!((r - 1.0).abs() < 1e-9 && (g - 1.0).abs() < 1e-9 && (b - 1.0).abs() < 1e-9);
    }
}
