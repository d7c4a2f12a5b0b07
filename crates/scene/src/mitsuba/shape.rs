//! Shapes: `obj`, `ply`, `serialized`, `rectangle`, `cube`, `disk`, `cylinder`, `sphere`, brought
//! to world space.
//!
//! Conventions (Mitsuba 3): positions are transformed by `to_world`, normals by its inverse
//! transpose. Mitsuba's `rectangle` and `disk` are analytic with normal `to_world · n`; their
//! tessellations here wind around that normal even under a mirroring `to_world`. The `cube`, `obj`
//! and `ply` are meshes in Mitsuba too and keep their winding (and per-vertex normals) as given.
//! `flip_normals` reverses the winding and negates the normals; `face_normals` drops per-vertex
//! normals, and a mesh file without them gets angle-weighted vertex normals otherwise (Mitsuba's
//! `recompute_vertex_normals`, in its `obj`, `ply` and `serialized` alike). The OBJ `flip_tex_coords` default (true) flips v as Mitsuba does. A shape has one BSDF
//! (default: diffuse 0.5) and at most one `area` emitter.

use super::bsdf::build_bsdf;
use super::emitter::build_area;
use super::props::Plugin;
use super::{expect_tag, Ctx};
use crate::desc::{Geometry, ShapeDesc, TriangleMesh};
use crate::error::SceneError;
use crate::shapes;
use ircache_math::{Mat3, Mat4, Vec2, Vec3};
use std::path::Path;
use std::rc::Rc;

const SHAPES: &[&str] = &[
    "obj",
    "ply",
    "serialized",
    "rectangle",
    "cube",
    "disk",
    "cylinder",
    "sphere",
    "shapegroup",
    "instance",
];

/// Builds a shape with its BSDF and optional area emitter.
pub(crate) fn build_shape(ctx: &Ctx, p: &Rc<Plugin>) -> Result<ShapeDesc, SceneError> {
    p.expect_type(SHAPES)?;
    if matches!(p.ty.as_str(), "shapegroup" | "instance") {
        return Err(p.error(format!(
            "a {} can appear only in <scene> (Mitsuba permits no nested groups or instancing)",
            p.ty
        )));
    }
    let to_world = p
        .transform_opt("to_world")?
        .map_or(Mat4::IDENTITY, |(m, _)| m);
    let flip = p.boolean("flip_normals", false)?;
    let geometry = match p.ty.as_str() {
        "sphere" => sphere(p, to_world, flip)?,
        "rectangle" | "disk" => {
            let mut mesh = if p.ty == "rectangle" {
                shapes::rectangle()
            } else {
                shapes::disk(shapes::DISK_SEGMENTS)
            };
            place_tessellated(p, &mut mesh, &to_world)?;
            finish_analytic(p, mesh, flip)?
        }
        "cylinder" => {
            // The unit cylinder placed on its axis p0 → p1 with its radius, then to_world.
            let p0 = p.vector_opt("p0")?.map_or(Vec3::ZERO, |(v, _)| v);
            let p1 = p.vector_opt("p1")?.map_or(Vec3::Z, |(v, _)| v);
            let radius = radius(p)?;
            let axis = p1 - p0;
            let length = axis.length();
            if !(length > 0.0 && length.is_finite()) {
                return Err(p.error("p0 and p1 must be distinct finite points"));
            }
            let frame = ircache_math::Frame::from_z(axis / length);
            let place = Mat4::from_cols(
                (frame.s * radius).extend(0.0),
                (frame.t * radius).extend(0.0),
                axis.extend(0.0),
                p0.extend(1.0),
            );
            let mut mesh = shapes::cylinder(shapes::DISK_SEGMENTS);
            place_tessellated(p, &mut mesh, &(to_world * place))?;
            if p.boolean("face_normals", false)? {
                mesh.normals = None;
            }
            finish_analytic(p, mesh, flip)?
        }
        "cube" => {
            let mut mesh = shapes::cube();
            if !shapes::transform_mesh(&mut mesh, &to_world) {
                return Err(p.error("to_world is singular (it collapses the shape to zero volume)"));
            }
            if p.boolean("face_normals", false)? {
                mesh.normals = None;
            }
            finish_analytic(p, mesh, flip)?
        }
        _ => {
            // obj, ply, serialized
            let (name, prop) = p
                .string_opt("filename")?
                .ok_or_else(|| p.error("missing \"filename\""))?;
            let path = ctx.resolve_file(name, prop)?;
            let loc = prop.loc.clone();
            let face_normals = p.boolean("face_normals", false)?;
            let mut mesh = if p.ty == "obj" {
                let flip_tex = p.boolean("flip_tex_coords", true)?;
                let mut m =
                    read_obj_mesh(ctx, &path).map_err(|e| attach_location(e, &loc, &path))?;
                // The reader gives Mitsuba's default (u, 1 − v); undo it when asked not to flip.
                if !flip_tex {
                    if let Some(uvs) = &mut m.uvs {
                        for uv in uvs {
                            *uv = Vec2::new(uv.x, 1.0 - uv.y);
                        }
                    }
                }
                m
            } else if p.ty == "ply" {
                // Mitsuba's `ply` keeps the file's texture coordinates unless asked to flip v.
                let flip_tex = p.boolean("flip_tex_coords", false)?;
                let mut m = read_ply_mesh(&path).map_err(|e| attach_location(e, &loc, &path))?;
                if flip_tex {
                    if let Some(uvs) = &mut m.uvs {
                        for uv in uvs {
                            *uv = Vec2::new(uv.x, 1.0 - uv.y);
                        }
                    }
                }
                m
            } else {
                let index = match p.integer_opt("shape_index")? {
                    None => 0,
                    Some((i, _)) if i >= 0 => i as usize,
                    Some((_, prop)) => {
                        return Err(SceneError::at(
                            prop.loc.clone(),
                            "shape_index must be non-negative",
                        ))
                    }
                };
                let m = crate::mesh::serialized::read_serialized(&path, index)
                    .map_err(|e| attach_location(e, &loc, &path))?;
                if m.degenerate_dropped > 0 {
                    ctx.notes.borrow_mut().push(format!(
                        "{}: mesh {index}: {} degenerate (zero-area) triangle{} dropped",
                        path.display(),
                        m.degenerate_dropped,
                        if m.degenerate_dropped == 1 { "" } else { "s" }
                    ));
                }
                m.mesh
            };
            if mesh.indices.is_empty() {
                return Err(SceneError::Referenced {
                    location: loc,
                    path,
                    message: "the mesh has no triangles".into(),
                });
            }
            if !shapes::transform_mesh(&mut mesh, &to_world) {
                return Err(p.error("to_world is singular"));
            }
            if face_normals {
                mesh.normals = None;
            } else if mesh.normals.is_none() {
                mesh.normals = Some(crate::mesh::compute_vertex_normals(&mesh));
            }
            if flip {
                shapes::flip_mesh(&mut mesh);
            }
            Geometry::Mesh(mesh)
        }
    };

    let mut bsdf = None;
    let mut emitter = None;
    let mut media = crate::desc::MediumInterface::default();
    for (obj, prop) in p.objects(&ctx.ids)? {
        match obj.tag.as_str() {
            "medium" => {
                let side = match prop.name.as_str() {
                    "interior" => &mut media.interior,
                    "exterior" => &mut media.exterior,
                    _ => {
                        return Err(SceneError::at(
                            prop.loc.clone(),
                            "a medium on a shape needs name=\"interior\" or name=\"exterior\"",
                        ))
                    }
                };
                *side = Some(super::medium::build_medium(ctx, &obj)?);
            }
            "bsdf" => {
                if bsdf.is_some() {
                    return Err(SceneError::at(
                        prop.loc.clone(),
                        "a shape can have only one BSDF",
                    ));
                }
                let built = build_bsdf(ctx, &obj)?;
                if !mask_placed_where_served(&built) {
                    return Err(SceneError::at(
                        prop.loc.clone(),
                        "a mask must wrap the shape's whole BSDF (or sit directly inside a \
                         one-sided twosided): deeper inside normal maps, bump maps or one side \
                         of a twosided it is not rendered",
                    ));
                }
                bsdf = Some(built);
            }
            "emitter" => {
                if emitter.is_some() {
                    return Err(SceneError::at(
                        prop.loc.clone(),
                        "a shape can have only one emitter",
                    ));
                }
                emitter = Some(build_area(ctx, &obj)?);
            }
            _ => expect_tag(&obj, prop, "bsdf, emitter or medium")?,
        }
    }
    p.check_unused()?;
    let (emitter, emitter_texture) = match emitter {
        Some((radiance, texture)) => (Some(radiance), texture),
        None => (None, None),
    };
    Ok(ShapeDesc {
        id: p.id.clone(),
        geometry,
        bsdf: bsdf.unwrap_or_else(|| ctx.default_bsdf.clone()),
        emitter,
        emitter_texture,
        emitter_pattern: None,
        media,
        location: p.loc.clone(),
    })
}

/// Mitsuba's `shapegroup` (built once per plugin): its shapes, in their own `to_world`s, which
/// only instances draw. Emitters cannot be instanced (as in Mitsuba).
pub(crate) fn build_group(ctx: &Ctx, p: &Rc<Plugin>) -> Result<Rc<Vec<ShapeDesc>>, SceneError> {
    let key = Rc::as_ptr(p);
    if let Some(g) = ctx.groups.borrow().get(&key) {
        return Ok(g.clone());
    }
    let mut shapes = Vec::new();
    for (obj, prop) in p.objects(&ctx.ids)? {
        expect_tag(&obj, prop, "shape")?;
        let shape = build_shape(ctx, &obj)?;
        if shape.emitter.is_some() {
            return Err(SceneError::at(
                obj.loc.clone(),
                "a shape in a shapegroup cannot be an emitter (Mitsuba does not instance emitters)",
            ));
        }
        shapes.push(shape);
    }
    p.check_unused()?;
    let group = Rc::new(shapes);
    ctx.groups.borrow_mut().insert(key, group.clone());
    Ok(group)
}

/// Mitsuba's `instance`: the shapes of the one `shapegroup` it refers to, placed by its
/// `to_world` (copied into world space: each instance's triangles are its own).
pub(crate) fn build_instance(ctx: &Ctx, p: &Rc<Plugin>) -> Result<Vec<ShapeDesc>, SceneError> {
    let to_world = p
        .transform_opt("to_world")?
        .map_or(Mat4::IDENTITY, |(m, _)| m);
    let objects = p.objects(&ctx.ids)?;
    let is_group = |obj: &Plugin| obj.tag == "shape" && obj.ty == "shapegroup";
    if let Some((_, prop)) = objects.iter().find(|(obj, _)| !is_group(obj)) {
        return Err(SceneError::at(
            prop.loc.clone(),
            "only a shapegroup can be given in an instance",
        ));
    }
    let group = match objects.as_slice() {
        [(obj, _)] => build_group(ctx, obj)?,
        [] => return Err(p.error("an instance needs a reference to a shapegroup")),
        [_, (_, prop), ..] => {
            return Err(SceneError::at(
                prop.loc.clone(),
                "an instance refers to one shapegroup only",
            ))
        }
    };
    p.check_unused()?;
    let scale = |v: Vec3| to_world.transform_vector3(v).length();
    let mut shapes = Vec::with_capacity(group.len());
    for shape in group.iter() {
        let mut shape = shape.clone();
        match &mut shape.geometry {
            Geometry::Mesh(mesh) => {
                if !shapes::transform_mesh(mesh, &to_world) {
                    return Err(p.error("to_world is singular"));
                }
            }
            Geometry::Sphere { center, radius, .. } => {
                let s = scale(Vec3::X);
                if [scale(Vec3::Y), scale(Vec3::Z)]
                    .iter()
                    .any(|t| (t / s - 1.0).abs() > 1e-3)
                {
                    return Err(
                        p.error("to_world must scale an instanced sphere alike along every axis")
                    );
                }
                *center = to_world.transform_point3(*center);
                *radius *= s;
            }
        }
        shapes.push(shape);
    }
    Ok(shapes)
}

fn finish_analytic(p: &Plugin, mut mesh: TriangleMesh, flip: bool) -> Result<Geometry, SceneError> {
    if let Some(t) = shapes::find_degenerate_triangle(&mesh) {
        return Err(p.error(format!(
            "to_world makes triangle {t} degenerate (zero area)"
        )));
    }
    if flip {
        shapes::flip_mesh(&mut mesh);
    }
    Ok(Geometry::Mesh(mesh))
}

/// A tessellated analytic shape (`rectangle`, `disk`, `cylinder`) brought to world space by
/// `m`, winding kept about the analytic shape's normal under a mirroring map.
fn place_tessellated(p: &Plugin, mesh: &mut TriangleMesh, m: &Mat4) -> Result<(), SceneError> {
    if !shapes::transform_mesh(mesh, m) {
        return Err(p.error("to_world is singular (it collapses the shape to zero area)"));
    }
    if Mat3::from_mat4(*m).determinant() < 0.0 {
        shapes::reverse_winding(mesh);
    }
    Ok(())
}

/// A `sphere`'s or `cylinder`'s `radius` (default 1), positive and finite.
fn radius(p: &Plugin) -> Result<f32, SceneError> {
    Ok(match p.float_opt("radius")? {
        None => 1.0,
        Some((r, _)) if r > 0.0 && r.is_finite() => r,
        Some((r, prop)) => {
            return Err(SceneError::at(
                prop.loc.clone(),
                format!("radius {r} must be positive"),
            ))
        }
    })
}

fn sphere(p: &Plugin, to_world: Mat4, flip: bool) -> Result<Geometry, SceneError> {
    let center = p.vector_opt("center")?.map_or(Vec3::ZERO, |(v, _)| v);
    let radius = radius(p)?;
    let lin = Mat3::from_mat4(to_world);
    let (cx, cy, cz) = (
        lin.x_axis.length(),
        lin.y_axis.length(),
        lin.z_axis.length(),
    );
    let s = (cx + cy + cz) / 3.0;
    let tol = 1e-4 * s;
    let orthogonal = lin.x_axis.dot(lin.y_axis).abs() <= tol * s
        && lin.y_axis.dot(lin.z_axis).abs() <= tol * s
        && lin.x_axis.dot(lin.z_axis).abs() <= tol * s;
    if !(s > 0.0 && s.is_finite())
        || (cx - s).abs() > tol
        || (cy - s).abs() > tol
        || (cz - s).abs() > tol
        || !orthogonal
    {
        return Err(p.error("to_world must be a rotation, translation and uniform scale (a sphere cannot be scaled non-uniformly or sheared)"));
    }
    let center = to_world.transform_point3(center);
    let radius = radius * s;
    if !center.is_finite() {
        return Err(p.error("sphere center is not finite"));
    }
    Ok(Geometry::Sphere {
        center,
        radius,
        flip_normals: flip,
        orientation: lin * (1.0 / s),
    })
}

/// Puts a location on a mesh reader's error when it has none.
fn attach_location(e: SceneError, loc: &crate::error::SourceLocation, path: &Path) -> SceneError {
    match e {
        SceneError::Io { path: _, source } => SceneError::Referenced {
            location: loc.clone(),
            path: path.to_path_buf(),
            message: source.to_string(),
        },
        SceneError::UnknownFormat { path: p } => SceneError::Referenced {
            location: loc.clone(),
            path: p,
            message: "unknown mesh format".into(),
        },
        other => other,
    }
}

/// Reads an OBJ file as Mitsuba's `obj` shape sees it: every group of the file in one mesh
/// (materials ignored; the shape's BSDF applies), texture coordinates already `(u, 1 − v)`.
fn read_obj_mesh(ctx: &Ctx, path: &Path) -> Result<TriangleMesh, SceneError> {
    let data = crate::mesh::obj::read_obj(path)?;
    if let Some(note) = crate::mesh::obj::degenerate_note(&data) {
        ctx.notes.borrow_mut().push(note);
    }
    Ok(crate::mesh::obj::obj_to_mesh(&data))
}

/// Reads a PLY file.
fn read_ply_mesh(path: &Path) -> Result<TriangleMesh, SceneError> {
    crate::mesh::ply::read_ply(path)
}

/// True when every `mask` in `bsdf` is where the renderer applies it: around the whole BSDF, or
/// as the single model of a `twosided` (both sides then masked).
fn mask_placed_where_served(bsdf: &crate::desc::BsdfDesc) -> bool {
    use crate::desc::BsdfDesc;
    fn has_mask(b: &BsdfDesc) -> bool {
        match b {
            BsdfDesc::Mask { .. } => true,
            BsdfDesc::TwoSided { front, back } => {
                has_mask(front) || back.as_deref().is_some_and(has_mask)
            }
            BsdfDesc::NormalMap { nested, .. } | BsdfDesc::BumpMap { nested, .. } => {
                has_mask(nested)
            }
            _ => false,
        }
    }
    match bsdf {
        BsdfDesc::Mask { nested, .. } => !has_mask(nested),
        BsdfDesc::TwoSided { front, back: None } => match front.as_ref() {
            BsdfDesc::Mask { nested, .. } => !has_mask(nested),
            other => !has_mask(other),
        },
        other => !has_mask(other),
    }
}
