//! Rigid tools from bundles: each v1 tool and contact as fem-core contact tools,
//! the `[[protocol.tools]]` extension, and the refusals, each naming the file,
//! the line and the key.

mod common;

use common::*;
use fem_core::press::{AnyPress, Attachment, Keyframe, Tool, ToolContact, ToolShape};
use wagashi_io::{read_bundle, write_bundle, BundleError, BundleWrite, ForceSample, ForceSeries};

/// A 20 x 10 x 8 mm elastic block pressed 1 mm in 10 s, held, released at 20 s.
const BLOCK: &str = gel_experiment!(
    "tools",
    3,
    r#"shape = "block"
size_mm = [20.0, 10.0, 8.0]
"#,
    r#"tool_contact = "glued"
support = "glued"
waypoints = [[0.0, 0.0], [10.0, 1.0], [20.0, 1.0]]
release_s = 20.0
end_s = 30.0
"#
);

/// The same gel as a cylinder, R = 6 mm, H = 10 mm.
fn cylinder(toml: &str) -> String {
    edit(
        toml,
        "shape = \"block\"\nsize_mm = [20.0, 10.0, 8.0]",
        "shape = \"cylinder\"\nradius_mm = 6.0\nheight_mm = 10.0",
    )
}

fn read(toml: &str) -> (TestBundle, wagashi_io::Bundle) {
    let b = bundle(&[("experiment.toml", toml)]);
    let read_back = read_bundle(&b.dir).unwrap_or_else(|e| panic!("{e}"));
    (b, read_back)
}

fn tools_of(problem: &AnyPress) -> (&[Tool], Attachment) {
    match problem {
        AnyPress::Solid(p) => (&p.tools, p.protocol.support),
        AnyPress::Plane(p) => (&p.tools, p.protocol.support),
        AnyPress::Axisymmetric(p) => (&p.tools, p.protocol.support),
    }
}

fn ys(tool: &Tool) -> Vec<f64> {
    tool.keyframes.iter().map(|k| k.translation_mm[1]).collect()
}

/// `[t_s, d_mm]` keyframes of a tool that starts at `start` and moves down by d(t).
fn moved(start: [f64; 3]) -> Vec<Keyframe> {
    [[0.0, 0.0], [10.0, 1.0], [20.0, 1.0]]
        .iter()
        .map(|&[t_s, d]| Keyframe { t_s, translation_mm: [start[0], start[1] - d, start[2]], rotation_rad: [0.0; 3] })
        .collect()
}

// ---- the v1 tools -----------------------------------------------------------

/// A sphere centred over the top face's centre, touching it at t = 0, moving
/// down by d(t): a block's (W/2, H + R, T/2), a cylinder's axis in 3D and in the
/// axisymmetric model, a plane block's (W/2, H + R, 0).
#[test]
fn a_sphere_touches_the_middle_of_the_top() {
    let sphere = edit(BLOCK, "tool = \"plate\"", "tool = \"sphere\"\ntool_radius_mm = 4.0");
    let sphere = edit(&sphere, "tool_contact = \"glued\"", "tool_contact = \"frictionless\"");
    let cases: Vec<(String, bool, [f64; 3])> = vec![
        (sphere.clone(), false, [10.0, 14.0, 4.0]),
        (edit(&sphere, "dimension = 3", "dimension = 2"), false, [10.0, 14.0, 0.0]),
        (cylinder(&sphere), false, [0.0, 14.0, 0.0]),
        (cylinder(&sphere), true, [0.0, 14.0, 0.0]),
    ];
    for (toml, axisymmetric, centre) in cases {
        let (_b, trial) = read(&toml);
        let problem =
            if axisymmetric { trial.to_press_axisymmetric(2.0).unwrap() } else { trial.to_press(2.0).unwrap() };
        let (tools, support) = tools_of(&problem);
        let expected = Tool {
            name: "sphere".into(),
            shape: ToolShape::Sphere { radius: 4.0 },
            contact: ToolContact::Frictionless,
            keyframes: moved(centre),
            release_s: 20.0,
            floor: false,
        };
        assert_eq!(tools, [expected], "{toml}");
        assert_eq!(support, Attachment::Glued);
    }
}

/// A punch: a flat cylinder of the radius, as tall as its diameter, its flat
/// lower face on the top at t = 0; glued until the release.
#[test]
fn a_punch_stands_on_the_top() {
    let toml = edit(BLOCK, "tool = \"plate\"", "tool = \"punch\"\ntool_radius_mm = 3.0");
    let (_b, trial) = read(&toml);
    let problem = trial.to_press(2.0).unwrap();
    let (tools, _) = tools_of(&problem);
    assert_eq!(tools.len(), 1);
    assert_eq!(tools[0].shape, ToolShape::Punch { radius: 3.0, half_height: 3.0 });
    assert_eq!(tools[0].keyframes, moved([10.0, 13.0, 4.0]));
    assert_eq!((tools[0].contact, tools[0].release_s), (ToolContact::Glued, 20.0));
}

/// A plate with friction is fem-core's plate above the specimen; a floor with
/// friction frees the bottom (Attachment::Free) and adds the floor tool, with a
/// glued plate as a contact tool too.
#[test]
fn friction_plates_and_floors_are_contact_tools() {
    let (lo, hi) = ([0.0; 3], [20.0, 10.0, 8.0]);
    let waypoints = [[0.0, 0.0], [10.0, 1.0], [20.0, 1.0]];

    let toml = edit(BLOCK, "tool_contact = \"glued\"", "tool_contact = \"friction\"\nfriction = 0.3");
    let (_b, trial) = read(&toml);
    let problem = trial.to_press(2.0).unwrap();
    let (tools, support) = tools_of(&problem);
    assert_eq!(tools, [Tool::plate_above("plate", lo, hi, &waypoints, ToolContact::Friction(0.3), 20.0)]);
    assert_eq!(support, Attachment::Glued);

    let toml = edit(BLOCK, "support = \"glued\"", "support = \"friction\"\nfriction = 0.5");
    let (_b, trial) = read(&toml);
    let problem = trial.to_press(2.0).unwrap();
    let (tools, support) = tools_of(&problem);
    assert_eq!(
        tools,
        [
            Tool::plate_above("plate", lo, hi, &waypoints, ToolContact::Glued, 20.0),
            Tool::floor_below("floor", lo, hi, ToolContact::Friction(0.5)),
        ]
    );
    assert!(tools[1].floor);
    assert_eq!(support, Attachment::Free);

    // In the axisymmetric model the plate and floor are those of the cylinder
    // [-R, R] x [0, H] x [-R, R], centred on the axis.
    let (_b, trial) = read(&cylinder(&toml));
    let problem = trial.to_press_axisymmetric(2.0).unwrap();
    let (tools, _) = tools_of(&problem);
    let (lo, hi) = ([-6.0, 0.0, -6.0], [6.0, 10.0, 6.0]);
    assert_eq!(tools[1], Tool::floor_below("floor", lo, hi, ToolContact::Friction(0.5)));
    assert_eq!(tools[0].keyframes[0].translation_mm[0], 0.0);
}

/// The seed's press keeps its constraints (no tool); a frictionless plate that
/// pushes again after rising (a double compression) is a contact tool; a rise
/// without a second push keeps the constraints.
#[test]
fn only_a_second_stroke_turns_the_frictionless_plate_into_a_tool() {
    for contact in ["glued", "frictionless"] {
        for support in ["glued", "frictionless"] {
            let toml = edit(BLOCK, "tool_contact = \"glued\"", &format!("tool_contact = \"{contact}\""));
            let toml = edit(&toml, "support = \"glued\"", &format!("support = \"{support}\""));
            let (_b, trial) = read(&toml);
            assert!(!trial.has_contact_tools());
            assert!(tools_of(&trial.to_press(2.0).unwrap()).0.is_empty());
        }
    }
    let strokes = "waypoints = [[0.0, 0.0], [10.0, 1.0], [11.0, -0.5], [15.0, -0.5], [20.0, 1.0], [21.0, -0.5]]\n\
                   release_s = 30.0";
    let double = edit(BLOCK, "waypoints = [[0.0, 0.0], [10.0, 1.0], [20.0, 1.0]]\nrelease_s = 20.0", strokes);
    let frictionless = edit(&double, "tool_contact = \"glued\"", "tool_contact = \"frictionless\"");
    let (_b, trial) = read(&frictionless);
    assert!(trial.has_contact_tools());
    let problem = trial.to_press(2.0).unwrap();
    let (tools, support) = tools_of(&problem);
    assert_eq!(tools.len(), 1);
    assert_eq!((tools[0].contact, support), (ToolContact::Frictionless, Attachment::Glued));
    // fem-core's plate above: half height 20 mm (the block's largest side), its
    // lower face on the top (y = 10) at t = 0.
    assert_eq!(ys(&tools[0]), [30.0, 29.0, 30.5, 30.5, 29.0, 30.5]);
    // Glued: held to the plate until the release whatever it does.
    assert!(!read(&double).1.has_contact_tools());
    // One rise (unloading until the release), no second push: the constraints.
    let unload = edit(
        &frictionless,
        "waypoints = [[0.0, 0.0], [10.0, 1.0], [11.0, -0.5], [15.0, -0.5], [20.0, 1.0], [21.0, -0.5]]",
        "waypoints = [[0.0, 0.0], [10.0, 1.0], [20.0, 0.2]]",
    );
    assert!(!read(&unload).1.has_contact_tools());
}

const TETRAHEDRON_OBJ: &str = "o tip\nv 0 12 0\nv 2 12 0\nv 0 12 2\nv 0 10 0\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

/// A surface tool stays where the file places it (mm for OBJ, or
/// `tool_surface_units`) and moves down by d(t); its regions are one body.
#[test]
fn a_surface_tool_stands_where_its_file_places_it() {
    let toml = edit(BLOCK, "tool = \"plate\"", "tool = \"surface\"\ntool_surface = \"tip.obj\"");
    let b = bundle(&[("experiment.toml", toml.as_str()), ("tip.obj", TETRAHEDRON_OBJ)]);
    let read_back = read_bundle(&b.dir).unwrap();
    let problem = read_back.to_press(2.0).unwrap();
    let (tools, _) = tools_of(&problem);
    let ToolShape::Mesh { vertices, triangles } = &tools[0].shape else { panic!("{:?}", tools[0].shape) };
    assert_eq!(vertices, &vec![[0.0, 12.0, 0.0], [2.0, 12.0, 0.0], [0.0, 12.0, 2.0], [0.0, 10.0, 0.0]]);
    assert_eq!(triangles.len(), 4);
    assert_eq!((tools[0].name.as_str(), tools[0].keyframes.clone()), ("surface", moved([0.0; 3])));

    // The same file in cm, with the tip at 10 mm: 100 mm.
    let toml = edit(&toml, "tool_surface = \"tip.obj\"", "tool_surface = \"tip.obj\"\ntool_surface_units = \"cm\"");
    let b = bundle(&[("experiment.toml", toml.as_str()), ("tip.obj", TETRAHEDRON_OBJ)]);
    let problem = read_bundle(&b.dir).unwrap().to_press(2.0).unwrap();
    let ToolShape::Mesh { vertices, .. } = &tools_of(&problem).0[0].shape else { panic!() };
    assert_eq!(vertices[3], [0.0, 100.0, 0.0]);
}

/// A surface tool outside the bundle folder (`..`, absolute, a symlink out) is
/// refused when the bundle is read, naming its key, and never read.
#[test]
fn a_surface_tool_outside_the_bundle_folder_is_refused() {
    let v1 = edit(BLOCK, "tool = \"plate\"", "tool = \"surface\"\ntool_surface = \"tip.obj\"");
    let extra = BLOCK.to_string()
        + &edit(TWO_TOOLS, "shape = \"sphere\"\nradius_mm = 2.0", "shape = \"surface\"\nsurface = \"tip.obj\"");
    for (toml, from, field) in [
        (v1.as_str(), "tool_surface = \"tip.obj\"", "protocol.tool_surface"),
        (extra.as_str(), "surface = \"tip.obj\"", "protocol.tools[0].surface"),
    ] {
        let key = from.split(" = ").next().unwrap();
        let mut names = vec!["../tip.obj".to_string(), "sub/../../tip.obj".to_string()];
        let b = bundle(&[("experiment.toml", toml)]);
        names.push(b.root.path().join("tip.obj").display().to_string());
        if cfg!(unix) {
            names.push("link.obj".to_string());
        }
        for name in names {
            let toml = edit(toml, from, &format!("{key} = \"{name}\""));
            let b = bundle(&[("experiment.toml", toml.as_str())]);
            std::fs::write(b.root.path().join("tip.obj"), TETRAHEDRON_OBJ).unwrap();
            #[cfg(unix)]
            std::os::unix::fs::symlink(b.root.path().join("tip.obj"), b.dir.join("link.obj")).unwrap();
            let line = line_of(&toml, &format!("{key} = "));
            let msg = assert_invalid(read_bundle(&b.dir), &b.file("experiment.toml"), line, field);
            assert!(msg.ends_with(": path leaves the bundle folder"), "{name}: {msg}");
        }
    }
}

/// A surface tool whose file is missing, or open, is refused on `tool_surface`'s line.
#[test]
fn a_surface_tool_must_be_a_readable_closed_surface() {
    let toml = edit(BLOCK, "tool = \"plate\"", "tool = \"surface\"\ntool_surface = \"tip.obj\"");
    let line = line_of(&toml, "tool_surface");
    let b = bundle(&[("experiment.toml", toml.as_str())]);
    let read_back = read_bundle(&b.dir).unwrap();
    let msg = assert_invalid(read_back.to_press(2.0), &b.file("experiment.toml"), line, "protocol.tool_surface");
    assert!(msg.contains("tip.obj") && msg.contains("cannot read"), "{msg}");

    let open = "v 0 12 0\nv 2 12 0\nv 0 12 2\nv 0 10 0\nf 1 3 2\nf 1 2 4\nf 1 4 3\n";
    let b = bundle(&[("experiment.toml", toml.as_str()), ("tip.obj", open)]);
    let read_back = read_bundle(&b.dir).unwrap();
    let msg = assert_invalid(read_back.to_press(2.0), &b.file("experiment.toml"), line, "protocol.tool_surface");
    assert!(msg.contains("closed"), "{msg}");

    let bad_unit = edit(&toml, "tool_surface = \"tip.obj\"", "tool_surface = \"tip.obj\"\ntool_surface_units = \"ft\"");
    let b = bundle(&[("experiment.toml", bad_unit.as_str()), ("tip.obj", TETRAHEDRON_OBJ)]);
    assert_invalid(
        read_bundle(&b.dir),
        &b.file("experiment.toml"),
        line_of(&bad_unit, "tool_surface_units"),
        "protocol.tool_surface_units",
    );
    let not_surface = edit(BLOCK, "tool = \"plate\"", "tool = \"plate\"\ntool_surface_units = \"mm\"");
    let b = bundle(&[("experiment.toml", not_surface.as_str())]);
    assert_invalid(
        read_bundle(&b.dir),
        &b.file("experiment.toml"),
        line_of(&not_surface, "tool_surface_units"),
        "protocol.tool_surface_units",
    );
}

// ---- [[protocol.tools]] -------------------------------------------------------

const TWO_TOOLS: &str = r#"
[[protocol.tools]]
name = "finger"
shape = "sphere"
radius_mm = 2.0
contact = "friction"
friction = 0.3
keyframes = [[0.0, 5.0, 12.0, 4.0], [5.0, 5.0, 12.0, 4.0], [15.0, 5.0, 11.0, 4.0], [25.0, 5.0, 14.0, 4.0]]

[[protocol.tools]]
name = "roller"
shape = "capsule"
radius_mm = 1.5
half_height_mm = 5.0
contact = "frictionless"
release_s = 25.0
keyframes = [[0.0, 15.0, 11.5, 4.0, 90.0, 0.0, 0.0], [10.0, 15.0, 11.0, 4.0, 90.0, 0.0, 0.0]]
"#;

/// Extra tools come after the v1 tool, with their shapes, contacts, releases
/// (default: the protocol's) and keyframes (degrees to radians).
#[test]
fn extra_tools_follow_their_keyframes() {
    let toml = edit(BLOCK, "tool_contact = \"glued\"", "tool_contact = \"frictionless\"") + TWO_TOOLS;
    let (_b, trial) = read(&toml);
    assert!(trial.has_contact_tools());
    let problem = trial.to_press(2.0).unwrap();
    let (tools, support) = tools_of(&problem);
    assert_eq!(support, Attachment::Glued);
    assert_eq!(tools.iter().map(|t| t.name.as_str()).collect::<Vec<_>>(), ["plate", "finger", "roller"]);
    assert_eq!(tools[0].contact, ToolContact::Frictionless);
    let finger = &tools[1];
    assert_eq!(
        (&finger.shape, finger.contact, finger.release_s, finger.floor),
        (&ToolShape::Sphere { radius: 2.0 }, ToolContact::Friction(0.3), 20.0, false)
    );
    assert_eq!(finger.keyframes.len(), 4);
    assert_eq!(finger.keyframes[2], Keyframe { t_s: 15.0, translation_mm: [5.0, 11.0, 4.0], rotation_rad: [0.0; 3] });
    let roller = &tools[2];
    assert_eq!(roller.shape, ToolShape::Capsule { radius: 1.5, half_height: 5.0 });
    assert_eq!((roller.contact, roller.release_s), (ToolContact::Frictionless, 25.0));
    assert!((roller.keyframes[1].rotation_rad[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert_eq!(roller.keyframes[1].translation_mm, [15.0, 11.0, 4.0]);
    for tool in tools {
        tool.validate().unwrap();
    }
    // Plates, punches (default half height: the radius) and surfaces too.
    let more = r#"
[[protocol.tools]]
name = "lid"
shape = "plate"
half_extents_mm = [3.0, 0.5, 3.0]
contact = "glued"
keyframes = [[0.0, 10.0, 10.5, 4.0]]

[[protocol.tools]]
name = "stamp"
shape = "punch"
radius_mm = 1.0
contact = "frictionless"
keyframes = [[0.0, 3.0, 11.0, 4.0]]

[[protocol.tools]]
name = "tip"
shape = "surface"
surface = "tip.obj"
units = "mm"
contact = "frictionless"
keyframes = [[0.0, 0.0, 0.0, 0.0], [1.0, 0.0, -1.0, 0.0]]
"#;
    let b = bundle(&[("experiment.toml", (BLOCK.to_string() + more).as_str()), ("tip.obj", TETRAHEDRON_OBJ)]);
    let problem = read_bundle(&b.dir).unwrap().to_press(2.0).unwrap();
    let (tools, _) = tools_of(&problem);
    assert_eq!(tools[1].shape, ToolShape::Plate { half_extents: [3.0, 0.5, 3.0] });
    assert_eq!(tools[2].shape, ToolShape::Punch { radius: 1.0, half_height: 1.0 });
    assert!(matches!(&tools[3].shape, ToolShape::Mesh { vertices, .. } if vertices[3] == [0.0, 10.0, 0.0]));
}

/// A bundle with extra tools is written back with them and reads back the same.
#[test]
fn extra_tools_survive_a_write_and_a_read() {
    let toml = BLOCK.to_string() + TWO_TOOLS;
    let (b, trial) = read(&toml);
    let force = ForceSeries { samples: vec![ForceSample { t_s: 0.0, force_n: 0.0 }] };
    let out = b.root.path().join("out");
    write_bundle(&out, &BundleWrite::simulated(&trial, "tools-sim", &force, &[])).unwrap();
    let back = read_bundle(&out).unwrap();
    assert_eq!(back.experiment.protocol, trial.experiment.protocol);
    assert_eq!(back.contact_tools(false).unwrap(), trial.contact_tools(false).unwrap());
}

/// In 2D the tools act in z = 0: a keyframe off that plane, or turning about x
/// or y, is refused when the bundle is read; in the axisymmetric model a tool
/// off the axis, or turning about x or z, when the model is built.
#[test]
fn extra_tools_in_2d_and_on_the_axis() {
    let plane = edit(BLOCK, "dimension = 3", "dimension = 2") + TWO_TOOLS;
    let b = bundle(&[("experiment.toml", plane.as_str())]);
    let msg = assert_invalid(
        read_bundle(&b.dir),
        &b.file("experiment.toml"),
        line_of(&plane, "keyframes = [[0.0, 5.0"),
        "protocol.tools[0].keyframes[0]",
    );
    assert!(msg.contains("z = 0"), "{msg}");
    let plane = plane.replace(", 4.0]", ", 0.0]").replace(", 4.0, 90.0, 0.0, 0.0]", ", 0.0, 0.0, 0.0, 90.0]");
    let (_b, trial) = read(&plane);
    let problem = trial.to_press(2.0).unwrap();
    assert!(matches!(problem, AnyPress::Plane(_)));
    assert!((tools_of(&problem).0[2].keyframes[0].rotation_rad[2] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);

    let axis = cylinder(BLOCK) + TWO_TOOLS;
    let (b, trial) = read(&axis);
    trial.to_press(2.0).unwrap();
    let msg = assert_invalid(
        trial.to_press_axisymmetric(2.0),
        &b.file("experiment.toml"),
        line_of(&axis, "keyframes = [[0.0, 5.0"),
        "protocol.tools[0].keyframes[0]",
    );
    assert!(msg.contains("axis"), "{msg}");
    let on_axis = axis.replace("5.0, 12.0, 4.0]", "0.0, 12.0, 0.0]").replace("5.0, 11.0, 4.0]", "0.0, 11.0, 0.0]");
    let on_axis = on_axis.replace("5.0, 14.0, 4.0]", "0.0, 14.0, 0.0]");
    let on_axis = on_axis.replace("15.0, 11.5, 4.0, 90.0, 0.0, 0.0]", "0.0, 11.5, 0.0, 0.0, 30.0, 0.0]");
    let (b, trial) = read(&on_axis);
    let msg = assert_invalid(
        trial.to_press_axisymmetric(2.0),
        &b.file("experiment.toml"),
        line_of(&on_axis, "keyframes = [[0.0, 0.0, 11.5"),
        "protocol.tools[1].keyframes[1]",
    );
    assert!(msg.contains("rz_deg = 0"), "{msg}");
    let on_axis = on_axis.replace("15.0, 11.0, 4.0, 90.0, 0.0, 0.0]", "0.0, 11.0, 0.0, 0.0, 30.0, 0.0]");
    let (_b, trial) = read(&on_axis);
    assert_eq!(tools_of(&trial.to_press_axisymmetric(2.0).unwrap()).0.len(), 3);
}

/// Each refusal of the extension names the file, the line and the key.
#[test]
fn extra_tool_refusals_name_the_key() {
    // (edit of TWO_TOOLS, the text on the line named (empty: the last line holding
    // the edit; `^TEXT`: the last line holding TEXT), the key named, a word of the
    // cause). A missing key is named on its table's header line.
    let cases: &[(&str, &str, &str, &str, &str)] = &[
        ("name = \"roller\"", "name = \"finger\"", "", "protocol.tools[1].name", "already"),
        ("name = \"roller\"", "name = \"plate\"", "name = \"plate\"", "protocol.tools[1].name", "taken"),
        ("name = \"roller\"", "name = \"floor\"", "name = \"floor\"", "protocol.tools[1].name", "taken"),
        ("name = \"roller\"", "name = \"a,b\"", "name = \"a,b\"", "protocol.tools[1].name", "commas"),
        ("name = \"roller\"", "name = \"../b\"", "name = \"../b\"", "protocol.tools[1].name", "slashes"),
        ("name = \"roller\"", "name = \"\"", "name = \"\"", "protocol.tools[1].name", "non-empty"),
        ("radius_mm = 2.0\n", "", "[[protocol.tools]]", "protocol.tools[0].radius_mm", "missing"),
        ("half_height_mm = 5.0\n", "", "^[[protocol.tools]]", "protocol.tools[1].half_height_mm", "missing"),
        ("radius_mm = 2.0", "radius_mm = -2.0", "radius_mm = -2.0", "protocol.tools[0].radius_mm", "> 0"),
        ("shape = \"sphere\"", "shape = \"plate\"", "[[protocol.tools]]", "protocol.tools[0].half_extents_mm", "missing"),
        (
            "shape = \"sphere\"\nradius_mm = 2.0",
            "shape = \"plate\"\nhalf_extents_mm = [1.0, 2.0]",
            "half_extents_mm",
            "protocol.tools[0].half_extents_mm",
            "three",
        ),
        (
            "shape = \"sphere\"\nradius_mm = 2.0",
            "shape = \"plate\"\nhalf_extents_mm = [1.0, 2.0, 1.0]\nradius_mm = 2.0",
            "radius_mm = 2.0",
            "protocol.tools[0].radius_mm",
            "not used",
        ),
        ("radius_mm = 2.0", "radius_mm = 2.0\nsurface = \"x.obj\"", "surface = ", "protocol.tools[0].surface", "not used"),
        ("shape = \"sphere\"\nradius_mm = 2.0", "shape = \"surface\"", "[[protocol.tools]]", "protocol.tools[0].surface", "missing"),
        ("friction = 0.3\n", "", "[[protocol.tools]]", "protocol.tools[0].friction", "missing"),
        ("friction = 0.3", "friction = -0.3", "friction = -0.3", "protocol.tools[0].friction", ">= 0"),
        ("release_s = 25.0", "release_s = 25.0\nfriction = 0.1", "friction = 0.1", "protocol.tools[1].friction", "not \"friction\""),
        ("release_s = 25.0", "release_s = 0.0", "release_s = 0.0", "protocol.tools[1].release_s", "> 0"),
        ("contact = \"frictionless\"", "contact = \"sticky\"", "contact = \"sticky\"", "protocol.tools[1].contact", "sticky"),
        ("shape = \"capsule\"", "shape = \"cube\"", "shape = \"cube\"", "protocol.tools[1].shape", "cube"),
        ("release_s = 25.0", "release_s = 25.0\nspeed = 1.0", "speed = 1.0", "protocol.tools[1].speed", "unknown key"),
        (
            "keyframes = [[0.0, 5.0, 12.0, 4.0], [5.0, 5.0, 12.0, 4.0], [15.0, 5.0, 11.0, 4.0], [25.0, 5.0, 14.0, 4.0]]",
            "keyframes = []",
            "keyframes = []",
            "protocol.tools[0].keyframes",
            "no keyframes",
        ),
        ("[5.0, 5.0, 12.0, 4.0]", "[5.0, 5.0, 12.0]", "keyframes = [[0.0, 5.0", "protocol.tools[0].keyframes[1]", "3 values"),
        (
            "[5.0, 5.0, 12.0, 4.0]",
            "[5.0, 5.0, 12.0, 4.0, 0.0, 0.0, 0.0]",
            "keyframes = [[0.0, 5.0",
            "protocol.tools[0].keyframes[1]",
            "same columns",
        ),
        ("[15.0, 5.0, 11.0, 4.0]", "[5.0, 5.0, 11.0, 4.0]", "keyframes = [[0.0, 5.0", "protocol.tools[0].keyframes[2]", "increasing"),
        ("[[0.0, 5.0, 12.0, 4.0]", "[[-1.0, 5.0, 12.0, 4.0]", "keyframes = [[-1.0", "protocol.tools[0].keyframes[0]", "negative"),
        ("[[0.0, 5.0, 12.0, 4.0]", "[[0.0, 5.0, nan, 4.0]", "keyframes = [[0.0, 5.0, nan", "protocol.tools[0].keyframes[0]", "finite"),
    ];
    for &(from, to, needle, field, cause) in cases {
        let toml = BLOCK.to_string() + &edit(TWO_TOOLS, from, to);
        let b = bundle(&[("experiment.toml", toml.as_str())]);
        let last = |text: &str| toml.lines().collect::<Vec<_>>().iter().rposition(|l| l.contains(text)).unwrap() + 1;
        let line = match needle.strip_prefix('^') {
            _ if needle.is_empty() => last(to),
            Some(text) => last(text),
            None => line_of(&toml, needle),
        };
        let msg = assert_invalid(read_bundle(&b.dir), &b.file("experiment.toml"), line, field);
        assert!(msg.contains(cause), "{from} -> {to}: expected `{cause}` in `{msg}`");
    }
    // The extra tools' surface files are read when the problem is built.
    let toml = BLOCK.to_string()
        + &edit(TWO_TOOLS, "shape = \"sphere\"\nradius_mm = 2.0", "shape = \"surface\"\nsurface = \"missing.obj\"");
    let b = bundle(&[("experiment.toml", toml.as_str())]);
    let read_back = read_bundle(&b.dir).unwrap();
    let err = read_back.to_press(2.0).unwrap_err();
    assert!(matches!(err, BundleError::Invalid { .. }));
    let want =
        format!("{}:{}: protocol.tools[0].surface: ", b.file("experiment.toml").display(), line_of(&toml, "surface ="));
    assert!(err.to_string().starts_with(&want) && err.to_string().contains("missing.obj"), "{err}");
}
