//! Bindings for `Transform` (the MathTransform of the SolidWorks API).

use super::api::Api;
use super::convert::{
    array3, box_text, err, fail, floats, num, numbers, numbers_into, point3, vec3,
};
use super::ScriptResult;
use crate::math::{format, Aabb, AngleConvention, Transform, Vec3};
use rhai::{Array, Dynamic};

fn matrix_array(t: &Transform) -> Dynamic {
    Dynamic::from_array(
        t.to_matrix()
            .iter()
            .map(|r| floats(r.iter().copied()))
            .collect(),
    )
}

/// A pose from `x y z` (mm) and `a b c` (degrees, XyzFixed).
pub fn pose_deg(v: &[f64; 6], conv: AngleConvention) -> Transform {
    Transform::from_xyzabc(
        Vec3::new(v[0], v[1], v[2]),
        [v[3].to_radians(), v[4].to_radians(), v[5].to_radians()],
        conv,
    )
}

/// `[x, y, z, a, b, c]`: mm and degrees.
pub fn xyzabc_deg(t: &Transform, conv: AngleConvention) -> Dynamic {
    floats(t.to_xyzabc_deg(conv))
}

/// A Transform from a script value: a Transform, a 4×4 matrix (mm) or a pose
/// `[x, y, z, a, b, c]` (mm, degrees).
pub fn to_transform(v: &Dynamic, what: &str) -> ScriptResult<Transform> {
    if let Some(t) = v.read_lock::<Transform>() {
        return Ok(*t);
    }
    let arr = v.read_lock::<Array>().ok_or_else(|| {
        fail(format!(
            "{what} must be a Transform or an array, not {}",
            v.type_name()
        ))
    })?;
    match arr.len() {
        4 => {
            let mut m = [[0.0; 4]; 4];
            for (i, row) in arr.iter().enumerate() {
                let r = numbers(row, 4, &format!("{what} row {}", i + 1))?;
                m[i].copy_from_slice(&r);
            }
            Transform::from_matrix(&m).map_err(fail)
        }
        6 => {
            let mut n = [0.0; 6];
            numbers_into(v, &mut n, what)?;
            Ok(pose_deg(&n, AngleConvention::default()))
        }
        // SolidWorks' ArrayData is in metres, fitup's matrices in mm: which one a
        // pasted list of 16 numbers is cannot be told, so the caller says it.
        16 => err(format!("{what}: 16 numbers are IMathTransform.ArrayData, whose translation SolidWorks gives in metres: write `create_transform(d)` for metres (as IMathUtility.CreateTransform) or `transform(d, \"mm\")` for millimetres")),
        n => err(format!("{what}: an array of {n} elements is not a 4×4 matrix (mm) or a pose [x,y,z,a,b,c] (mm, degrees); 16 ArrayData numbers go to `create_transform(d)` (metres) or `transform(d, \"mm\")`")),
    }
}

/// The 4×4 matrix (document layout) of a 4×4 array or 16 ArrayData numbers, with the
/// translation converted from `unit` (`"mm"` or `"m"`) to mm.
fn matrix_in(v: &Dynamic, unit: &str, what: &str) -> ScriptResult<[[f64; 4]; 4]> {
    let scale = match unit {
        "mm" => 1.0,
        "m" => 1000.0,
        u => return err(format!("{what}: unit must be \"mm\" or \"m\", not {u:?}")),
    };
    let arr = v
        .read_lock::<Array>()
        .ok_or_else(|| fail(format!("{what} must be an array, not {}", v.type_name())))?;
    let mut m = [[0.0; 4]; 4];
    match arr.len() {
        4 => {
            for (i, row) in arr.iter().enumerate() {
                let r = numbers(row, 4, &format!("{what} row {}", i + 1))?;
                m[i].copy_from_slice(&r);
            }
        }
        16 => {
            let d = numbers(v, 16, what)?;
            m = [
                [d[0], d[1], d[2], d[13]],
                [d[3], d[4], d[5], d[14]],
                [d[6], d[7], d[8], d[15]],
                [d[9], d[10], d[11], d[12]],
            ];
        }
        n => {
            return err(format!(
                "{what}: an array of {n} elements is neither a 4×4 matrix nor 16 ArrayData numbers"
            ))
        }
    }
    for v in &mut m[3][..3] {
        *v *= scale;
    }
    Ok(m)
}

/// `v` for people: numbers to `decimals` places without noise or `-0`, arrays element
/// by element, Transforms as `X … C …°` poses (see [`crate::math::format`]).
fn fmt_value(v: &Dynamic, decimals: usize) -> String {
    if let Ok(x) = v.as_float() {
        return format::number(x, decimals);
    }
    if let Ok(i) = v.as_int() {
        return i.to_string();
    }
    if let Some(t) = v.read_lock::<Transform>() {
        return t.to_string();
    }
    if let Some(b) = v.read_lock::<Aabb>() {
        let v = |p: &crate::math::Point3| {
            let items: Vec<String> = p.iter().map(|x| format::number(*x, decimals)).collect();
            format!("[{}]", items.join(", "))
        };
        return format!("#{{min: {}, max: {}}}", v(&b.lo), v(&b.hi));
    }
    if let Some(a) = v.read_lock::<Array>() {
        let items: Vec<String> = a.iter().map(|x| fmt_value(x, decimals)).collect();
        return format!("[{}]", items.join(", "));
    }
    if let Some(m) = v.read_lock::<rhai::Map>() {
        let items: Vec<String> = m
            .iter()
            .map(|(k, x)| format!("{k}: {}", fmt_value(x, decimals)))
            .collect();
        return format!("#{{{}}}", items.join(", "));
    }
    v.to_string()
}

fn decimals(d: i64) -> ScriptResult<usize> {
    if (0..=format::MAX_DECIMALS as i64).contains(&d) {
        Ok(d as usize)
    } else {
        err(format!(
            "decimals must be 0 to {}, not {d}",
            format::MAX_DECIMALS
        ))
    }
}

fn convention(name: &str) -> ScriptResult<AngleConvention> {
    AngleConvention::parse(name).ok_or_else(|| {
        fail(format!(
            "unknown angle convention `{name}`: use \"xyz\" (seed 000) or \"zyx\" (seed 001)"
        ))
    })
}

pub(super) fn register(api: &mut Api) {
    api.section("Transform", "Rigid poses in the SolidWorks pose-matrix layout: 4 rows `[a b c 0] [d e f 0] [g h i 0] [j k l 1]`, rotation in a..i, translation j k l in mm, acting on row vectors (`[x y z 1] · M`). `a * b` applies `a` first, then `b` (like IMathTransform.Multiply). Pose triples `X Y Z A B C` are mm and degrees; default convention `xyz`: A about the fixed X axis, then B about fixed Y, then C about fixed Z (R = Rz(C)·Ry(B)·Rx(A)); `zyx` is seed 001's: rotate Z by A, then the new Y by B, then the new X by C.");
    api.type_::<Transform>("Transform");
    api.f("identity() -> Transform", "The identity pose.", || {
        Transform::IDENTITY
    });
    api.f(
        "translation(x, y, z) -> Transform",
        "A pure translation by (x, y, z) mm.",
        |x: Dynamic, y: Dynamic, z: Dynamic| -> ScriptResult<Transform> {
            Ok(Transform::from_translation(Vec3::new(
                num(&x, "x")?,
                num(&y, "y")?,
                num(&z, "z")?,
            )))
        },
    );
    api.f(
        "translation(v: array) -> Transform",
        "A pure translation by [x, y, z] mm.",
        |v: Dynamic| -> ScriptResult<Transform> {
            Ok(Transform::from_translation(vec3(&v, "translation")?))
        },
    );
    api.f("rotation(point: array, axis: array, angle_rad) -> Transform", "A rotation of `angle_rad` **radians** (right hand) about the line through `point` (mm) along `axis`.", |p: Dynamic, a: Dynamic, ang: Dynamic| -> ScriptResult<Transform> {
        Transform::from_rotation_about(point3(&p, "point")?, vec3(&a, "axis")?, num(&ang, "angle")?).map_err(fail)
    });
    api.f("pose(x, y, z, a, b, c) -> Transform", "A pose from position (mm) and angles A B C in **degrees** (convention `xyz`, see the section).", |x: Dynamic, y: Dynamic, z: Dynamic, a: Dynamic, b: Dynamic, c: Dynamic| -> ScriptResult<Transform> {
        Ok(pose_deg(&[num(&x, "x")?, num(&y, "y")?, num(&z, "z")?, num(&a, "a")?, num(&b, "b")?, num(&c, "c")?], AngleConvention::default()))
    });
    api.f(
        "pose(xyzabc: array) -> Transform",
        "A pose from `[x, y, z, a, b, c]` (mm, degrees, convention `xyz`).",
        |v: Dynamic| -> ScriptResult<Transform> {
            let n = numbers(&v, 6, "pose")?;
            Ok(pose_deg(
                &[n[0], n[1], n[2], n[3], n[4], n[5]],
                AngleConvention::default(),
            ))
        },
    );
    api.f(
        "pose(xyzabc: array, convention: string) -> Transform",
        "A pose from `[x, y, z, a, b, c]` (mm, degrees) in convention `\"xyz\"` or `\"zyx\"`.",
        |v: Dynamic, conv: &str| -> ScriptResult<Transform> {
            let n = numbers(&v, 6, "pose")?;
            Ok(pose_deg(
                &[n[0], n[1], n[2], n[3], n[4], n[5]],
                convention(conv)?,
            ))
        },
    );
    api.f("transform(m: array) -> Transform", "A Transform from a 4×4 matrix (layout above, mm) or a pose `[x,y,z,a,b,c]` (mm, degrees); checks that it is rigid. 16 ArrayData numbers are refused here (SolidWorks gives their translation in metres): use `create_transform(d)` (metres) or `transform(d, \"mm\")`.", |m: Dynamic| to_transform(&m, "transform"));
    api.get(
        "Transform.matrix -> array",
        "The 4×4 matrix, rows `[a b c 0] [d e f 0] [g h i 0] [j k l 1]` (mm).",
        |t: &mut Transform| matrix_array(t),
    );
    api.f("transform(m: array, unit: string) -> Transform", "A Transform from a 4×4 matrix (layout above) or 16 IMathTransform.ArrayData numbers (a..i, j k l, scale, n o p) whose translation is in `unit`: `\"mm\"` or `\"m\"`; checks that it is rigid.", |m: Dynamic, unit: &str| -> ScriptResult<Transform> {
        Transform::from_matrix(&matrix_in(&m, unit, "transform")?).map_err(fail)
    });
    api.f("create_transform(array_data: array) -> Transform", "SolidWorks' IMathUtility.CreateTransform: 16 ArrayData numbers a..i, j k l (**metres**, as SolidWorks gives them), scale, n o p; checks that it is rigid (see `orthonormalize` for rounded rotations).", |d: Dynamic| -> ScriptResult<Transform> {
        if d.read_lock::<Array>().is_none_or(|a| a.len() != 16) {
            return err("create_transform: ArrayData is 16 numbers (a..i, j k l in metres, scale, n o p)");
        }
        Transform::from_matrix(&matrix_in(&d, "m", "create_transform")?).map_err(fail)
    });
    api.f("orthonormalize(m: array) -> Transform", "The rigid pose nearest to a 4×4 matrix (mm) whose rotation was rounded (a spreadsheet's digits): the nearest rotation to the a..i block, the translation as given. Refuses a mirror, and a block more than 0.01 from a rotation (that is not rounding).", |m: Dynamic| -> ScriptResult<Transform> {
        Transform::orthonormalized(&matrix_in(&m, "mm", "orthonormalize")?).map_err(fail)
    });
    api.f("orthonormalize(m: array, unit: string) -> Transform", "`orthonormalize` of a 4×4 matrix or 16 ArrayData numbers whose translation is in `unit` (`\"mm\"` or `\"m\"`).", |m: Dynamic, unit: &str| -> ScriptResult<Transform> {
        Transform::orthonormalized(&matrix_in(&m, unit, "orthonormalize")?).map_err(fail)
    });
    api.get(
        "Transform.array_data -> array",
        "The 16 numbers of IMathTransform.ArrayData in SolidWorks' units: a..i, j k l in **metres**, scale 1, 0 0 0 (`create_transform` reads them back).",
        |t: &mut Transform| floats(t.to_array_data_si()),
    );
    api.get(
        "Transform.array_data_mm -> array",
        "`array_data` with the translation j k l in mm (`transform(d, \"mm\")` reads it back).",
        |t: &mut Transform| floats(t.to_array_data()),
    );
    api.get(
        "Transform.xyzabc -> array",
        "`[x, y, z, a, b, c]`: mm and degrees, convention `xyz`.",
        |t: &mut Transform| xyzabc_deg(t, AngleConvention::default()),
    );
    api.f(
        "Transform.xyzabc_in(convention: string) -> array",
        "`[x, y, z, a, b, c]` (mm, degrees) in convention `\"xyz\"` or `\"zyx\"`.",
        |t: &mut Transform, conv: &str| -> ScriptResult<Dynamic> {
            Ok(xyzabc_deg(t, convention(conv)?))
        },
    );
    api.get(
        "Transform.translation -> array",
        "The translation `[j, k, l]` (mm).",
        |t: &mut Transform| array3(&t.translation()),
    );
    api.f(
        "Transform.inverse() -> Transform",
        "The inverse pose.",
        |t: &mut Transform| t.inverse(),
    );
    api.f(
        "Transform.apply(point: array) -> array",
        "Maps a point `[x, y, z]` (mm) through the pose.",
        |t: &mut Transform, p: Dynamic| -> ScriptResult<Dynamic> {
            Ok(array3(&t.apply(&point3(&p, "point")?).coords))
        },
    );
    api.f(
        "Transform.apply_vector(v: array) -> array",
        "Rotates a direction `[x, y, z]` (no translation).",
        |t: &mut Transform, v: Dynamic| -> ScriptResult<Dynamic> {
            Ok(array3(&t.apply_vector(&vec3(&v, "vector")?)))
        },
    );
    api.f(
        "Transform.interpolate(other: Transform, s) -> Transform",
        "Straight-line translation and slerp rotation, `s` from 0 (self) to 1 (other).",
        |t: &mut Transform, o: Transform, s: Dynamic| -> ScriptResult<Transform> {
            Ok(t.interpolate(&o, num(&s, "s")?))
        },
    );
    api.f(
        "Transform.distance_to(other: Transform) -> map",
        "`#{mm, deg}`: translation distance (mm) and rotation angle (degrees) between two poses.",
        |t: &mut Transform, o: Transform| {
            let (a, d) = t.distance_to(&o);
            let mut m = rhai::Map::new();
            m.insert("mm".into(), Dynamic::from_float(d));
            m.insert("deg".into(), Dynamic::from_float(a.to_degrees()));
            m
        },
    );
    api.f(
        "Transform * Transform -> Transform",
        "Composition: apply the left pose, then the right one (row-vector product).",
        |a: Transform, b: Transform| a * b,
    );
    api.f(
        "Transform == Transform -> bool",
        "Equal within 1e-9 mm and 1e-9 rad.",
        |a: Transform, b: Transform| a.approx_eq(&b, 1e-9, 1e-9),
    );
    api.f(
        "Transform != Transform -> bool",
        "Not equal within 1e-9 mm and 1e-9 rad.",
        |a: Transform, b: Transform| !a.approx_eq(&b, 1e-9, 1e-9),
    );
    api.f(
        "Transform.to_string() -> string",
        "The pose for people, `X 10 Y 0 Z 5 A 0° B 0° C 90°` (mm, degrees, convention `xyz`, 0.001 resolution); what `print` and `${t}` show.",
        |t: &mut Transform| t.to_string(),
    );
    api.f(
        "Transform.to_debug() -> string",
        "The 4×4 matrix at full precision, rows `[a b c 0] [d e f 0] [g h i 0] [j k l 1]` (mm).",
        |t: &mut Transform| format!("{t:?}"),
    );
    api.f(
        "deg(rad) -> float",
        "Radians to degrees.",
        |r: Dynamic| -> ScriptResult<f64> { Ok(num(&r, "rad")?.to_degrees()) },
    );
    api.f(
        "rad(deg) -> float",
        "Degrees to radians.",
        |d: Dynamic| -> ScriptResult<f64> { Ok(num(&d, "deg")?.to_radians()) },
    );
    api.section("Box", "An axis-aligned box (mm), as `aabb()` and `cells()` return it; where an option takes a box (`bounds`), a map `#{min: [x,y,z], max: [x,y,z]}` works too.");
    api.type_::<Aabb>("Box");
    api.get(
        "Box.min -> array",
        "The minimum corner `[x, y, z]` (mm).",
        |b: &mut Aabb| array3(&b.lo.coords),
    );
    api.get(
        "Box.max -> array",
        "The maximum corner `[x, y, z]` (mm).",
        |b: &mut Aabb| array3(&b.hi.coords),
    );
    api.get(
        "Box.centre -> array",
        "The centre `[x, y, z]` (mm).",
        |b: &mut Aabb| array3(&b.centre().coords),
    );
    api.get(
        "Box.size -> array",
        "The edge lengths `[dx, dy, dz]` (mm).",
        |b: &mut Aabb| array3(&(b.hi - b.lo)),
    );
    api.overload("to_string(b: Box)", |b: &mut Aabb| box_text(b));
    api.overload("to_debug(b: Box)", |b: &mut Aabb| box_text(b));
    api.section("Formatting", "Numbers for people: `fmt` rounds to a number of decimals (3 by default: 0.001 mm, 0.001°), drops trailing zeros and rounding noise (`29.999999999999996` → `30`, `6.4e-15` → `0`), never prints `-0`, and writes magnitudes of 10¹⁵ and more as `1e308`. Plain `print(x)` and `${x}` keep every digit (use them for data you will read back).");
    api.f(
        "fmt(value) -> string",
        "A number with up to 3 decimals; an array, map or Box element by element; a Transform as its pose (`X 10 Y 0 Z 5 A 0° B 0° C 90°`); anything else as `to_string`.",
        |v: Dynamic| fmt_value(&v, format::DEFAULT_DECIMALS),
    );
    api.f(
        "fmt(value, decimals: int) -> string",
        "Like `fmt(value)` with `decimals` places (0 to 15) for numbers, also inside arrays and maps.",
        |v: Dynamic, d: i64| -> ScriptResult<String> { Ok(fmt_value(&v, decimals(d)?)) },
    );
    api.f(
        "fmt_mm(length) -> string",
        "A length in mm for people: `12.5 mm` (0.001 mm resolution).",
        |v: Dynamic| -> ScriptResult<String> { Ok(format::length(num(&v, "length")?)) },
    );
    api.f(
        "fmt_deg(angle_deg) -> string",
        "An angle **already in degrees** for people: `30°` (0.001° resolution); for radians write `fmt_deg(deg(r))`.",
        |v: Dynamic| -> ScriptResult<String> { Ok(format::degrees(num(&v, "angle")?)) },
    );
}
