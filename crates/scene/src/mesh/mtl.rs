//! Wavefront MTL material-library reader.
//!
//! Reads `newmtl`, `Kd`, `Ks`, `Ke`, `Ka` (colours: one value for grey or three for RGB), `Ns`,
//! `Ni`, `d`, `Tr`, `illum`, and the texture statements `map_Kd`, `map_Ks`, `map_Ka`, `map_Ke`,
//! `map_bump`/`bump`, `map_d`, `disp`, `norm` (recorded with their file name; texture options such
//! as `-bm 1`, `-o u v w`, `-clamp on` are skipped). Other statements are ignored, as are statements
//! before the first `newmtl`. Malformed numbers are errors naming `file:line:column`; so are the
//! spectral (`Kd spectral f.rfl`) and CIE XYZ (`Kd xyz ...`) colour forms, which are not supported.
//! A material defined twice keeps its last definition.

use super::obj::{for_each_statement, parse_number, parse_numbers, Token};
use crate::error::{SceneError, SourceLocation};
use ircache_math::Rgb;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One `newmtl` material. Colours not written are `None`, so that callers choose defaults.
#[derive(Clone, Debug)]
pub struct MtlMaterial {
    /// The `newmtl` name.
    pub name: String,
    /// Where `newmtl` was written.
    pub location: SourceLocation,
    /// `Ka`, ambient colour.
    pub ambient: Option<Rgb>,
    /// `Kd`, diffuse colour.
    pub diffuse: Option<Rgb>,
    /// `Ks`, specular colour.
    pub specular: Option<Rgb>,
    /// `Ke`, emitted radiance.
    pub emission: Option<Rgb>,
    /// `Ns`, Phong exponent.
    pub shininess: Option<f32>,
    /// `Ni`, index of refraction.
    pub ior: Option<f32>,
    /// Opacity: `d`, or `1 − Tr`.
    pub dissolve: Option<f32>,
    /// `illum`, the illumination model number.
    pub illum: Option<i32>,
    /// `map_Kd`, diffuse texture.
    pub map_kd: Option<MtlTexture>,
    /// `map_Ks`, specular texture.
    pub map_ks: Option<MtlTexture>,
    /// `map_Ka`, ambient texture.
    pub map_ka: Option<MtlTexture>,
    /// `map_Ke`, emission texture.
    pub map_ke: Option<MtlTexture>,
    /// `map_bump` or `bump`, bump map (recorded only).
    pub map_bump: Option<MtlTexture>,
    /// `map_d`, opacity texture (recorded only).
    pub map_d: Option<MtlTexture>,
    /// `disp`, displacement map (recorded only).
    pub disp: Option<MtlTexture>,
    /// `norm`, normal map (recorded only).
    pub norm: Option<MtlTexture>,
}

/// A texture reference in an MTL file.
#[derive(Clone, Debug, PartialEq)]
pub struct MtlTexture {
    /// The file name as written (relative to the MTL file's folder unless absolute).
    pub path: PathBuf,
    /// The `-bm` bump multiplier, if given.
    pub bump_multiplier: Option<f32>,
    /// Where the statement was written.
    pub location: SourceLocation,
}

impl MtlMaterial {
    fn new(name: String, location: SourceLocation) -> MtlMaterial {
        MtlMaterial {
            name,
            location,
            ambient: None,
            diffuse: None,
            specular: None,
            emission: None,
            shininess: None,
            ior: None,
            dissolve: None,
            illum: None,
            map_kd: None,
            map_ks: None,
            map_ka: None,
            map_ke: None,
            map_bump: None,
            map_d: None,
            disp: None,
            norm: None,
        }
    }
}

/// Reads an MTL file; see the [module documentation](self).
pub fn read_mtl(path: &Path) -> Result<Vec<MtlMaterial>, SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_mtl(
        &String::from_utf8_lossy(&bytes),
        Arc::new(path.to_path_buf()),
    )
}

/// Parses MTL text; `file` is the name used in error locations. Materials come in file order,
/// without duplicates (a redefinition replaces the earlier one in place).
pub fn parse_mtl(text: &str, file: Arc<PathBuf>) -> Result<Vec<MtlMaterial>, SceneError> {
    let mut out: Vec<MtlMaterial> = Vec::new();
    let mut current: Option<usize> = None;
    for_each_statement(text, |toks| {
        let kw = toks[0].text;
        if kw == "newmtl" {
            if toks.len() < 2 {
                return Err(SceneError::at(
                    toks[0].end_location(&file),
                    "expected a material name after 'newmtl'",
                ));
            }
            let name = super::obj::rest_of_statement(toks);
            let m = MtlMaterial::new(name, toks[0].location(&file));
            if let Some(i) = out.iter().position(|x| x.name == m.name) {
                out[i] = m;
                current = Some(i);
            } else {
                out.push(m);
                current = Some(out.len() - 1);
            }
            return Ok(());
        }
        let Some(i) = current else { return Ok(()) };
        let m = &mut out[i];
        match kw {
            "Ka" => m.ambient = Some(colour(toks, &file)?),
            "Kd" => m.diffuse = Some(colour(toks, &file)?),
            "Ks" => m.specular = Some(colour(toks, &file)?),
            "Ke" => m.emission = Some(colour(toks, &file)?),
            "Ns" => m.shininess = Some(single(toks, &file)?),
            "Ni" => m.ior = Some(single(toks, &file)?),
            "d" => m.dissolve = Some(dissolve(toks, &file)?),
            "Tr" => m.dissolve = Some(1.0 - single(toks, &file)?),
            "illum" => {
                let [v] = parse_numbers::<1>(toks, &file, 1, 1)?;
                if v.fract() != 0.0 || !(0.0..=i32::MAX as f32).contains(&v) {
                    return Err(SceneError::at(
                        toks[1].location(&file),
                        format!(
                            "expected an illumination model number after 'illum', found '{}'",
                            toks[1].text
                        ),
                    ));
                }
                m.illum = Some(v as i32);
            }
            "map_Kd" => m.map_kd = Some(texture(toks, &file)?),
            "map_Ks" => m.map_ks = Some(texture(toks, &file)?),
            "map_Ka" => m.map_ka = Some(texture(toks, &file)?),
            "map_Ke" => m.map_ke = Some(texture(toks, &file)?),
            "map_bump" | "map_Bump" | "bump" => m.map_bump = Some(texture(toks, &file)?),
            "map_d" => m.map_d = Some(texture(toks, &file)?),
            "disp" => m.disp = Some(texture(toks, &file)?),
            "norm" => m.norm = Some(texture(toks, &file)?),
            _ => {}
        }
        Ok(())
    })?;
    Ok(out)
}

fn single(toks: &[Token], file: &Arc<PathBuf>) -> Result<f32, SceneError> {
    let [v] = parse_numbers::<1>(toks, file, 1, 1)?;
    Ok(v)
}

/// `d [-halo] value`.
fn dissolve(toks: &[Token], file: &Arc<PathBuf>) -> Result<f32, SceneError> {
    if toks.len() == 3 && toks[1].text == "-halo" {
        return parse_number(&toks[2], file, "d");
    }
    single(toks, file)
}

/// `K? r [g b]`.
fn colour(toks: &[Token], file: &Arc<PathBuf>) -> Result<Rgb, SceneError> {
    if let Some(t) = toks.get(1) {
        if t.text == "spectral" || t.text == "xyz" {
            return Err(SceneError::at(
                t.location(file),
                format!(
                    "'{} {}' colours are not supported (use RGB values)",
                    toks[0].text, t.text
                ),
            ));
        }
    }
    if toks.len() == 3 {
        return Err(SceneError::at(
            toks[2].end_location(file),
            format!("expected 1 or 3 numbers after '{}', found 2", toks[0].text),
        ));
    }
    let [r, g, b] = parse_numbers::<3>(toks, file, 1, 3)?;
    Ok(if toks.len() == 2 {
        Rgb::splat(r)
    } else {
        Rgb::new(r, g, b)
    })
}

/// Arguments of each texture option: (least, most, numeric). `-o`, `-s`, `-t` take 1 to 3 numbers.
fn option_arity(name: &str) -> Option<(usize, usize, bool)> {
    Some(match name {
        "-blendu" | "-blendv" | "-cc" | "-clamp" | "-imfchan" | "-type" => (1, 1, false),
        "-bm" | "-boost" | "-texres" => (1, 1, true),
        "-mm" => (2, 2, true),
        "-o" | "-s" | "-t" => (1, 3, true),
        _ => return None,
    })
}

/// `map_?? [options] file name`.
fn texture(toks: &[Token], file: &Arc<PathBuf>) -> Result<MtlTexture, SceneError> {
    let kw = toks[0].text;
    let mut i = 1;
    let mut bump_multiplier = None;
    while i < toks.len() {
        let Some((min, max, numeric)) = option_arity(toks[i].text) else {
            break;
        };
        let opt = toks[i].text;
        let mut taken = 0;
        while taken < max {
            let Some(t) = toks.get(i + 1 + taken) else {
                break;
            };
            if numeric && t.text.parse::<f32>().is_err() {
                if taken < min {
                    return Err(SceneError::at(
                        t.location(file),
                        format!("expected a number after '{opt}', found '{}'", t.text),
                    ));
                }
                break;
            }
            taken += 1;
        }
        if taken < min {
            return Err(SceneError::at(
                toks[i + taken].end_location(file),
                format!("expected an argument after texture option '{opt}'"),
            ));
        }
        if opt == "-bm" && taken >= 1 {
            bump_multiplier = toks[i + 1]
                .text
                .parse::<f32>()
                .ok()
                .filter(|x| x.is_finite());
        }
        i += 1 + taken;
    }
    if i >= toks.len() {
        let last = toks.last().unwrap_or(&toks[0]);
        return Err(SceneError::at(
            last.end_location(file),
            format!("expected a file name after '{kw}'"),
        ));
    }
    let path = toks[i..]
        .iter()
        .map(|t| t.text)
        .collect::<Vec<_>>()
        .join(" ");
    Ok(MtlTexture {
        path: PathBuf::from(path),
        bump_multiplier,
        location: toks[0].location(file),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Vec<MtlMaterial>, SceneError> {
        parse_mtl(text, Arc::new(PathBuf::from("t.mtl")))
    }

    #[test]
    fn reads_materials() {
        let m = parse(
            "newmtl a\r\n\tKd 0.5 0.25 1 # c\r\n\tKs 0.1\r\nNs 20\r\nKe 17 12 4\r\nd 0.5\r\nillum 2\r\n\
             map_Kd -bm 0.5 -o 1 2 -clamp on tex dir/a b.png\r\nbump -bm 1 b.jpg\r\nnewmtl b\r\nTr 0.25\r\n",
        )
        .unwrap();
        assert_eq!(m.len(), 2);
        assert_eq!(m[0].diffuse, Some(Rgb::new(0.5, 0.25, 1.0)));
        assert_eq!(m[0].specular, Some(Rgb::splat(0.1)));
        assert_eq!(m[0].shininess, Some(20.0));
        assert_eq!(m[0].emission, Some(Rgb::new(17.0, 12.0, 4.0)));
        assert_eq!(m[0].illum, Some(2));
        assert_eq!(m[0].dissolve, Some(0.5));
        assert_eq!(
            m[0].map_kd.as_ref().unwrap().path,
            PathBuf::from("tex dir/a b.png")
        );
        assert_eq!(m[0].map_kd.as_ref().unwrap().location.line, 8);
        assert_eq!(m[0].map_bump.as_ref().unwrap().path, PathBuf::from("b.jpg"));
        assert_eq!(m[1].dissolve, Some(0.75));
    }

    #[test]
    fn errors() {
        let e = parse("newmtl a\n  Kd 0.5 zz 1\n").unwrap_err().to_string();
        assert_eq!(e, "t.mtl:2:10: expected a number after 'Kd', found 'zz'");
        let e = parse("newmtl a\nmap_Kd -bm\n").unwrap_err().to_string();
        assert_eq!(
            e,
            "t.mtl:2:11: expected an argument after texture option '-bm'"
        );
        let e = parse("newmtl a\nmap_Kd -bm 1\n").unwrap_err().to_string();
        assert_eq!(e, "t.mtl:2:13: expected a file name after 'map_Kd'");
        let e = parse("newmtl\n").unwrap_err().to_string();
        assert_eq!(e, "t.mtl:1:7: expected a material name after 'newmtl'");
    }
}
