//! Bindings for mass properties (`mass_properties`) and the overlap of interfering
//! components (`overlap`: intersection volume and interference depth).

use super::api::Api;
use super::bind_document::{ComponentHandle, DocHandle};
use super::bind_files::options;
use super::bind_math::to_transform;
use super::bind_planning::with_workspace;
use super::convert::{array3, fail, floats, point3};
use super::ScriptResult;
use crate::mesh::MassProperties;
use crate::workspace::{mass_properties, MassOptions, OverlapOptions};
use nalgebra::Matrix3;
use rhai::{Array, Dynamic, Map};

fn matrix(m: &Matrix3<f64>) -> Dynamic {
    Dynamic::from_array((0..3).map(|i| floats((0..3).map(|j| m[(i, j)]))).collect())
}

fn indices(d: &DocHandle, names: &Array) -> ScriptResult<Vec<usize>> {
    let doc = d.lock()?;
    names
        .iter()
        .map(|n| {
            let s = n
                .clone()
                .into_string()
                .map_err(|t| fail(format!("component names must be strings, not {t}")))?;
            doc.component_index(&s).map_err(fail)
        })
        .collect()
}

fn of(d: &DocHandle, which: Option<Vec<usize>>, o: &MassOptions) -> ScriptResult<MassProperties> {
    let doc = d.lock()?;
    let all: Vec<usize> = (0..doc.components().len())
        .filter(|&i| !doc.components()[i].is_suppressed())
        .collect();
    mass_properties(&doc, which.as_deref().unwrap_or(&all), o).map_err(fail)
}

pub(super) fn register(api: &mut Api) {
    api.section("Mass properties", "Volume, mass, centre of mass and inertia of components, a selection or the whole assembly (SolidWorks' `IMassProperty`), exact for the closed meshes (signed tetrahedra). Units: mm, mm², mm³, kg, kg·mm², density kg/m³. A component's mass is its `mass:` (kg) when the document gives one, else the call's `density` (default 1000 kg/m³). Results are in world coordinates; `in_frame(t)` re-expresses them in a coordinate system. The inertia tensor has the physics sign (`Ixy = −∫xy dm`, as trimesh and URDF); `moments` has SolidWorks' (`Lxy = +∫xy dm`). Meshes that are not closed solids are refused, naming the component.");
    api.type_::<MassProperties>("MassProperties");
    api.f(
        "Document.mass_properties() -> MassProperties",
        "The whole assembly's mass properties (every component).",
        |d: &mut DocHandle| of(d, None, &MassOptions::default()),
    );
    api.f("Document.mass_properties(selection: array) -> MassProperties", "The mass properties of the named components together (SolidWorks' mass properties of a selection).", |d: &mut DocHandle, names: Array| -> ScriptResult<MassProperties> {
        let which = indices(d, &names)?;
        of(d, Some(which), &MassOptions::default())
    });
    api.f("Document.mass_properties(selection: array, options: map) -> MassProperties", "As above with `#{density}` (kg/m³, for components without `mass:`); an empty selection means every component.", |d: &mut DocHandle, names: Array, o: Map| -> ScriptResult<MassProperties> {
        let o: MassOptions = options(&o, "mass_properties")?;
        let which = (!names.is_empty()).then(|| indices(d, &names)).transpose()?;
        of(d, which, &o)
    });
    api.f("Component.mass_properties() -> MassProperties", "The component's mass properties in world coordinates (`in_frame(c.transform)` gives them in its part frame).", |c: &mut ComponentHandle| of(&c.doc, Some(vec![c.index()?]), &MassOptions::default()));
    api.f(
        "Component.mass_properties(options: map) -> MassProperties",
        "As above with `#{density}` (kg/m³).",
        |c: &mut ComponentHandle, o: Map| -> ScriptResult<MassProperties> {
            let o: MassOptions = options(&o, "mass_properties")?;
            of(&c.doc, Some(vec![c.index()?]), &o)
        },
    );
    api.get(
        "MassProperties.volume -> float",
        "Volume, mm³.",
        |m: &mut MassProperties| m.volume,
    );
    api.get(
        "MassProperties.mass -> float",
        "Mass, kg.",
        |m: &mut MassProperties| m.mass,
    );
    api.get(
        "MassProperties.area -> float",
        "Surface area, mm².",
        |m: &mut MassProperties| m.area,
    );
    api.get(
        "MassProperties.density -> float",
        "Mass over volume, kg/m³.",
        |m: &mut MassProperties| m.density(),
    );
    api.get(
        "MassProperties.centre_of_mass -> array",
        "Centre of mass `[x, y, z]`, mm (SolidWorks' `CenterOfMass`, in mm).",
        |m: &mut MassProperties| array3(&m.centre_of_mass.coords),
    );
    api.get("MassProperties.inertia -> array", "The inertia tensor about the centre of mass, axes of the frame, kg·mm², 3×3 rows (physics sign: off-diagonals `−∫xy dm`).", |m: &mut MassProperties| matrix(&m.inertia));
    api.get("MassProperties.moments -> array", "SolidWorks' moments of inertia at the centre of mass `[[Lxx, Lxy, Lxz], [Lyx, Lyy, Lyz], [Lzx, Lzy, Lzz]]`, kg·mm² (`Lxy = +∫xy dm`).", |m: &mut MassProperties| {
        let s = m.solidworks_moments();
        Dynamic::from_array((0..3).map(|i| floats(s[3 * i..3 * i + 3].iter().copied())).collect())
    });
    api.get(
        "MassProperties.principal_moments -> array",
        "Principal moments `[Px, Py, Pz]` ascending, kg·mm².",
        |m: &mut MassProperties| floats(m.principal().0),
    );
    api.get("MassProperties.principal_axes -> array", "The principal axes (unit vectors, a right-handed set) in the order of `principal_moments`.", |m: &mut MassProperties| Dynamic::from_array(m.principal().1.iter().map(array3).collect()));
    api.f("MassProperties.inertia_about(point: array) -> array", "The inertia tensor about `point` (mm, same frame) with the frame's axes, kg·mm² (parallel-axis theorem; SolidWorks' \"taken at the output coordinate system\" for the origin).", |m: &mut MassProperties, p: Dynamic| -> ScriptResult<Dynamic> {
        Ok(matrix(&m.inertia_about(&point3(&p, "point")?)))
    });
    api.f("MassProperties.in_frame(frame) -> MassProperties", "The properties expressed in the coordinate system whose pose (in the current frame, mm) is `frame` (a Transform, 4×4 matrix or `[x,y,z,a,b,c]`): SolidWorks' output coordinate system.", |m: &mut MassProperties, f: Dynamic| -> ScriptResult<MassProperties> {
        Ok(m.in_frame(&to_transform(&f, "frame")?))
    });
    api.get("MassProperties.si -> map", "The same numbers in SolidWorks' API units: `#{volume (m³), mass (kg), area (m²), density (kg/m³), centre_of_mass (m), moments (kg·m², SolidWorks' sign)}`.", |m: &mut MassProperties| {
        let mut out = Map::new();
        out.insert("volume".into(), Dynamic::from_float(m.volume * 1e-9));
        out.insert("mass".into(), Dynamic::from_float(m.mass));
        out.insert("area".into(), Dynamic::from_float(m.area * 1e-6));
        out.insert("density".into(), Dynamic::from_float(m.density()));
        out.insert("centre_of_mass".into(), array3(&(m.centre_of_mass.coords / 1000.0)));
        let s = m.solidworks_moments();
        out.insert("moments".into(), Dynamic::from_array((0..3).map(|i| floats(s[3 * i..3 * i + 3].iter().map(|v| v * 1e-6))).collect()));
        out
    });
    api.f(
        "MassProperties.to_string() -> string",
        "`MassProperties(mass kg, volume mm³, centre [x, y, z] mm)`.",
        |m: &mut MassProperties| {
            let c = m.centre_of_mass;
            format!(
                "MassProperties({:.6} kg, {:.3} mm³, centre [{:.3}, {:.3}, {:.3}] mm)",
                m.mass, m.volume, c.x, c.y, c.z
            )
        },
    );

    api.section("Overlap", "How much two interfering components overlap, exactly for closed meshes: the intersection volume (SolidWorks' interference volume) and the interference depth — the shortest straight translation that takes the first component out of the second, on curved parts too (a screw pushed 5 mm into a table reads 5 mm).");
    api.f("Document.overlap(a: string, b: string) -> map", "`#{volume (mm³), depth (mm), direction ([x,y,z], the unit world direction `a` moves out along)}`; all 0 when they only touch or are apart. Budget 10 s.", |d: &mut DocHandle, a: &str, b: &str| -> ScriptResult<Map> {
        overlap(d, a, b, &OverlapOptions::default())
    });
    api.f(
        "Document.overlap(a: string, b: string, options: map) -> map",
        "As above with `#{time_limit_ms}`.",
        |d: &mut DocHandle, a: &str, b: &str, o: Map| -> ScriptResult<Map> {
            let o: OverlapOptions = options(&o, "overlap")?;
            overlap(d, a, b, &o)
        },
    );
}

fn overlap(d: &DocHandle, a: &str, b: &str, o: &OverlapOptions) -> ScriptResult<Map> {
    let v = with_workspace(d, |ws| ws.overlap(a, b, o).map_err(fail))?;
    let mut m = Map::new();
    m.insert("volume".into(), Dynamic::from_float(v.volume));
    m.insert("depth".into(), Dynamic::from_float(v.depth));
    m.insert("direction".into(), array3(&v.direction));
    Ok(m)
}

/// The components and frame of an export's options map, and `overwrite`.
fn export_options(
    d: &DocHandle,
    o: &Map,
    default: Vec<usize>,
) -> ScriptResult<(Vec<usize>, Option<crate::math::Transform>, bool)> {
    super::convert::check_keys(o, &["components", "frame", "overwrite"], "export_stl")?;
    let which = match o.get("components") {
        Some(v) => {
            let names = v
                .read_lock::<Array>()
                .ok_or_else(|| fail("option `components` must be an array of names"))?
                .clone();
            indices(d, &names)?
        }
        None => default,
    };
    let frame = o
        .get("frame")
        .map(|f| to_transform(f, "frame"))
        .transpose()?;
    let overwrite = match o.get("overwrite") {
        Some(v) => v
            .as_bool()
            .map_err(|t| fail(format!("option `overwrite` must be true or false, not {t}")))?,
        None => false,
    };
    Ok((which, frame, overwrite))
}

fn export_stl(
    d: &DocHandle,
    file: &str,
    which: &[usize],
    frame: Option<&crate::math::Transform>,
    overwrite: bool,
) -> ScriptResult<()> {
    let bytes = {
        let doc = d.lock()?;
        crate::mesh::stl_bytes(&crate::workspace::world_mesh(&doc, which, frame).map_err(fail)?)
    };
    d.context().write_output(file, &bytes, overwrite)?;
    Ok(())
}

pub(super) fn register_export(api: &mut Api) {
    api.section("Export", "Component meshes with their pose baked in (CodeStack's \"Export Part Or Component To STL\", \"Export Relative To Coordinate System\"): binary STL in mm, in world coordinates or in a coordinate system `frame` (its pose in the world: a Transform, 4×4 matrix or `[x,y,z,a,b,c]`). Writers go through the write rule (see \"What a run writes\" in docs/scripting.md).");
    api.f("Component.world_mesh() -> map", "The component's mesh at its pose: `#{vertices: [[x,y,z], …] (mm, world), triangles: [[i,j,k], …]}`.", |c: &mut ComponentHandle| -> ScriptResult<Map> {
        let mesh = {
            let (doc, i) = c.locked()?;
            crate::workspace::world_mesh(&doc, &[i], None).map_err(fail)?
        };
        let mut m = Map::new();
        m.insert("vertices".into(), Dynamic::from_array(mesh.vertices.iter().map(|p| array3(&p.coords)).collect()));
        m.insert("triangles".into(), Dynamic::from_array(mesh.triangles.iter().map(|t| Dynamic::from_array(t.iter().map(|&i| Dynamic::from_int(i64::from(i))).collect())).collect()));
        Ok(m)
    });
    api.f(
        "Component.export_stl(file: string)",
        "Writes the component's mesh at its pose (world, mm) as binary STL.",
        |c: &mut ComponentHandle, file: &str| -> ScriptResult<()> {
            export_stl(&c.doc, file, &[c.index()?], None, false)
        },
    );
    api.f(
        "Component.export_stl(file: string, options: map)",
        "As above with `#{frame, overwrite}`.",
        |c: &mut ComponentHandle, file: &str, o: Map| -> ScriptResult<()> {
            let (which, frame, overwrite) = export_options(&c.doc, &o, vec![c.index()?])?;
            export_stl(&c.doc, file, &which, frame.as_ref(), overwrite)
        },
    );
    api.f("Document.export_stl(file: string, options: map)", "Writes components at their poses as one binary STL: `#{components: [names] (default all), frame, overwrite}`.", |d: &mut DocHandle, file: &str, o: Map| -> ScriptResult<()> {
        let all: Vec<usize> = {
            let doc = d.lock()?;
            (0..doc.components().len())
                .filter(|&i| doc.components()[i].is_shown())
                .collect()
        };
        let (which, frame, overwrite) = export_options(d, &o, all)?;
        export_stl(d, file, &which, frame.as_ref(), overwrite)
    });
}
