//! Writes [`SceneParts`] as a GLB: the JSON document through `gltf-json`, one binary buffer.

use std::borrow::Cow;
use std::collections::{BTreeMap, HashMap};

use glam::{DQuat, DVec3};
use gltf::json;
use json::validation::Checked::Valid;
use json::validation::USize64;
use sitar_core::{Convention, ErrorClass, Pose};

use crate::shapes::{self, JOINT_RADIUS, Shape};
use crate::{Error, SceneParts};

/// The shapes a node can show.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum ShapeKind {
    Cylinder,
    Joint,
    Endpoint,
    Frustum,
    Exclamation,
    WarningSign,
    /// A unit cube (venue cells).
    Cube,
}

impl ShapeKind {
    fn build(self) -> Shape {
        match self {
            Self::Cylinder => shapes::cylinder(),
            Self::Joint => shapes::sphere(JOINT_RADIUS),
            Self::Endpoint => shapes::sphere(JOINT_RADIUS * 3.0),
            Self::Frustum => shapes::frustum(),
            Self::Exclamation => shapes::exclamation(),
            Self::WarningSign => shapes::warning_sign(),
            Self::Cube => shapes::cube(),
        }
    }

    fn name(self) -> &'static str {
        match self {
            Self::Cylinder => "segment",
            Self::Joint => "joint",
            Self::Endpoint => "endpoint",
            Self::Frustum => "frustum",
            Self::Exclamation => "exclamation",
            Self::WarningSign => "warning_sign",
            Self::Cube => "cube",
        }
    }

    fn mode(self) -> json::mesh::Mode {
        match self {
            Self::Frustum => json::mesh::Mode::Lines,
            _ => json::mesh::Mode::Triangles,
        }
    }
}

/// Materials: the four classes and the scene's other colours.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Paint {
    Class(ErrorClass),
    Frustum,
    Start,
    Stop,
    Surface,
    /// A venue's surface cell: translucent, by class.
    SurfaceCell(ErrorClass),
    /// A venue's path cell: faint, by class.
    PathCell(ErrorClass),
    /// The venue's anchor image.
    Anchor,
}

impl Paint {
    fn name(self) -> &'static str {
        match self {
            Self::Class(c) => c.name(),
            Self::Frustum => "frustum",
            Self::Start => "start",
            Self::Stop => "stop",
            Self::Surface => "surface_point",
            Self::SurfaceCell(c) => match c {
                ErrorClass::Low => "surface_cell_low",
                ErrorClass::Medium => "surface_cell_medium",
                ErrorClass::High => "surface_cell_high",
                ErrorClass::Unknown => "surface_cell_unknown",
            },
            Self::PathCell(c) => match c {
                ErrorClass::Low => "path_cell_low",
                ErrorClass::Medium => "path_cell_medium",
                ErrorClass::High => "path_cell_high",
                ErrorClass::Unknown => "path_cell_unknown",
            },
            Self::Anchor => "anchor",
        }
    }

    /// Opacity: cells are see-through so the room (and the cells behind) stay visible.
    fn alpha(self) -> f32 {
        match self {
            Self::SurfaceCell(_) => 0.55,
            Self::PathCell(_) => 0.25,
            _ => 1.0,
        }
    }

    /// sRGB colour, as the report draws it.
    fn srgb(self) -> u32 {
        match self {
            Self::Class(c) | Self::SurfaceCell(c) | Self::PathCell(c) => match c {
                ErrorClass::Low => 0x2f6fde,
                ErrorClass::Medium => 0xe0b100,
                ErrorClass::High => 0xd62728,
                ErrorClass::Unknown => 0x9a9a9a,
            },
            Self::Anchor => 0x222222,
            Self::Frustum => 0x555555,
            Self::Start => 0x2ca02c,
            Self::Stop => 0x111111,
            Self::Surface => 0x8c564b,
        }
    }

    /// glTF colour factors are linear.
    fn linear_rgba(self) -> [f32; 4] {
        let c = self.srgb();
        let lin = |byte: u32| {
            let v = (byte & 0xff) as f32 / 255.0;
            if v <= 0.04045 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        };
        [lin(c >> 16), lin(c >> 8), lin(c), self.alpha()]
    }
}

/// A shape's accessors: positions, normals (triangles only), indices.
type Geometry = (
    json::Index<json::Accessor>,
    Option<json::Index<json::Accessor>>,
    json::Index<json::Accessor>,
);

/// The document being built and its binary chunk.
pub(crate) struct Writer {
    pub(crate) root: json::Root,
    bin: Vec<u8>,
    /// Geometry accessors per shape: (positions, normals, indices).
    geometry: HashMap<ShapeKind, Geometry>,
    meshes: HashMap<(ShapeKind, Paint), json::Index<json::Mesh>>,
    materials: HashMap<Paint, json::Index<json::Material>>,
}

const BUFFER: u32 = 0;

pub(crate) fn f32_of(v: f64, what: &str) -> Result<f32, Error> {
    let x = v as f32;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(Error::Encode(format!(
            "{what} is not a finite number ({v})"
        )))
    }
}

pub(crate) fn vec3(v: DVec3, what: &str) -> Result<[f32; 3], Error> {
    Ok([f32_of(v.x, what)?, f32_of(v.y, what)?, f32_of(v.z, what)?])
}

fn quat(q: DQuat, what: &str) -> Result<json::scene::UnitQuaternion, Error> {
    let q = q.normalize();
    Ok(json::scene::UnitQuaternion([
        f32_of(q.x, what)?,
        f32_of(q.y, what)?,
        f32_of(q.z, what)?,
        f32_of(q.w, what)?,
    ]))
}

pub(crate) fn extras(value: serde_json::Value) -> Result<json::Extras, Error> {
    serde_json::value::RawValue::from_string(value.to_string())
        .map(Some)
        .map_err(|e| Error::Encode(e.to_string()))
}

impl Writer {
    pub(crate) fn new() -> Writer {
        let mut root = json::Root::default();
        root.asset.generator = Some(format!("sitar-scene {}", env!("CARGO_PKG_VERSION")));
        Writer {
            root,
            bin: Vec::new(),
            geometry: HashMap::new(),
            meshes: HashMap::new(),
            materials: HashMap::new(),
        }
    }

    /// Appends `bytes` as one buffer view (4-byte aligned, as accessors need).
    fn view(
        &mut self,
        bytes: &[u8],
        target: json::buffer::Target,
    ) -> json::Index<json::buffer::View> {
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.root.push(json::buffer::View {
            buffer: json::Index::new(BUFFER),
            byte_length: USize64::from(bytes.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            extensions: None,
            extras: None,
            name: None,
            target: Some(Valid(target)),
        })
    }

    fn vec3_accessor(&mut self, data: &[[f32; 3]], bounds: bool) -> json::Index<json::Accessor> {
        let bytes: Vec<u8> = data
            .iter()
            .flat_map(|v| v.iter().flat_map(|c| c.to_le_bytes()))
            .collect();
        let view = self.view(&bytes, json::buffer::Target::ArrayBuffer);
        let (min, max) = if bounds {
            let mut lo = [f32::MAX; 3];
            let mut hi = [f32::MIN; 3];
            for v in data {
                for k in 0..3 {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
            (
                Some(json::Value::from(lo.to_vec())),
                Some(json::Value::from(hi.to_vec())),
            )
        } else {
            (None, None)
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(data.len()),
            component_type: Valid(json::accessor::GenericComponentType(
                json::accessor::ComponentType::F32,
            )),
            extensions: None,
            extras: None,
            type_: Valid(json::accessor::Type::Vec3),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    fn index_accessor(&mut self, data: &[u16]) -> json::Index<json::Accessor> {
        let bytes: Vec<u8> = data.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes, json::buffer::Target::ElementArrayBuffer);
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(data.len()),
            component_type: Valid(json::accessor::GenericComponentType(
                json::accessor::ComponentType::U16,
            )),
            extensions: None,
            extras: None,
            type_: Valid(json::accessor::Type::Scalar),
            min: None,
            max: None,
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    fn material(&mut self, paint: Paint) -> json::Index<json::Material> {
        if let Some(m) = self.materials.get(&paint) {
            return *m;
        }
        let mut material = json::Material {
            name: Some(paint.name().into()),
            // Warning signs are plates: visible from both sides.
            double_sided: true,
            alpha_mode: Valid(if paint.alpha() < 1.0 {
                json::material::AlphaMode::Blend
            } else {
                json::material::AlphaMode::Opaque
            }),
            ..Default::default()
        };
        material.pbr_metallic_roughness.base_color_factor =
            json::material::PbrBaseColorFactor(paint.linear_rgba());
        material.pbr_metallic_roughness.metallic_factor = json::material::StrengthFactor(0.0);
        material.pbr_metallic_roughness.roughness_factor = json::material::StrengthFactor(0.8);
        let index = self.root.push(material);
        self.materials.insert(paint, index);
        index
    }

    pub(crate) fn mesh(&mut self, kind: ShapeKind, paint: Paint) -> json::Index<json::Mesh> {
        if let Some(m) = self.meshes.get(&(kind, paint)) {
            return *m;
        }
        let (positions, normals, indices) = match self.geometry.get(&kind) {
            Some(g) => *g,
            None => {
                let shape = kind.build();
                let p = self.vec3_accessor(&shape.positions, true);
                let n = shape.normals.as_ref().map(|n| self.vec3_accessor(n, false));
                let i = self.index_accessor(&shape.indices);
                self.geometry.insert(kind, (p, n, i));
                (p, n, i)
            }
        };
        let mut attributes = BTreeMap::new();
        attributes.insert(Valid(json::mesh::Semantic::Positions), positions);
        if let Some(n) = normals {
            attributes.insert(Valid(json::mesh::Semantic::Normals), n);
        }
        let material = self.material(paint);
        let index = self.root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: Some(format!("{}_{}", kind.name(), paint.name())),
            primitives: vec![json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: None,
                indices: Some(indices),
                material: Some(material),
                mode: Valid(kind.mode()),
                targets: None,
            }],
            weights: None,
        });
        self.meshes.insert((kind, paint), index);
        index
    }

    pub(crate) fn node(&mut self, node: json::Node) -> json::Index<json::Node> {
        self.root.push(node)
    }

    /// The GLB of a scene with one root node.
    pub(crate) fn finish(mut self, root: json::Index<json::Node>) -> Result<Vec<u8>, Error> {
        let scene = self.root.push(json::Scene {
            extensions: None,
            extras: None,
            name: Some("sitar".into()),
            nodes: vec![root],
        });
        self.root.scene = Some(scene);
        let bin_len = self.bin.len();
        self.root.buffers.push(json::Buffer {
            byte_length: USize64::from(bin_len),
            extensions: None,
            extras: None,
            name: None,
            uri: None,
        });
        let text =
            json::serialize::to_string(&self.root).map_err(|e| Error::Encode(e.to_string()))?;
        let length = 12 + 8 + text.len().next_multiple_of(4) + 8 + bin_len.next_multiple_of(4);
        let glb = gltf::binary::Glb {
            header: gltf::binary::Header {
                magic: *b"glTF",
                version: 2,
                length: u32::try_from(length)
                    .map_err(|_| Error::Encode(format!("{length} bytes exceed GLB's 4 GiB")))?,
            },
            json: Cow::Owned(text.into_bytes()),
            bin: Some(Cow::Owned(self.bin)),
        };
        glb.to_vec().map_err(|e| Error::Encode(e.to_string()))
    }

    /// A group node over `children` (glTF forbids an empty `children` array).
    pub(crate) fn group(
        &mut self,
        name: &str,
        children: Vec<json::Index<json::Node>>,
    ) -> json::Index<json::Node> {
        self.node(json::Node {
            name: Some(name.into()),
            children: (!children.is_empty()).then_some(children),
            ..Default::default()
        })
    }
}

/// A pose in glTF's frame: the session convention converted to ARCore's (see the crate docs).
fn to_gltf(convention: Convention, pose: Pose) -> Pose {
    convention.convert_pose(pose, Convention::Arcore)
}

/// The scene of `parts` as a binary glTF 2.0 file (see the crate docs for its layout).
pub fn to_glb(parts: &SceneParts) -> Result<Vec<u8>, Error> {
    let plan = &parts.plan;
    if plan.joints.is_empty() {
        return Err(Error::NoTrajectory);
    }
    let conv = parts.convention;
    let point = |p: DVec3| conv.convert_vector(p, Convention::Arcore);
    let rotation = |q: DQuat| conv.convert_rotation(q, Convention::Arcore);
    let mut w = Writer::new();

    let mut segments = Vec::with_capacity(plan.segments.len());
    for (i, s) in plan.segments.iter().enumerate() {
        let class = parts.class_of(s.subtrajectory);
        let mesh = w.mesh(ShapeKind::Cylinder, Paint::Class(class));
        let node = json::Node {
            name: Some(format!("segment_{i}")),
            mesh: Some(mesh),
            translation: Some(vec3(point(s.centre), "segment centre")?),
            rotation: Some(quat(rotation(s.rotation), "segment rotation")?),
            // A zero-length step still gets a (vanishingly short) node, so counts match the plan.
            scale: Some([1.0, f32_of(s.length.max(1e-6), "segment length")?, 1.0]),
            extras: extras(
                serde_json::json!({"subtrajectory": s.subtrajectory, "class": class.name()}),
            )?,
            ..Default::default()
        };
        segments.push(w.node(node));
    }
    let mut joints = Vec::with_capacity(plan.joints.len());
    for (i, j) in plan.joints.iter().enumerate() {
        let mesh = w.mesh(
            ShapeKind::Joint,
            Paint::Class(parts.class_of(j.subtrajectory)),
        );
        let node = json::Node {
            name: Some(format!("joint_{i}")),
            mesh: Some(mesh),
            translation: Some(vec3(point(j.position), "joint position")?),
            extras: extras(serde_json::json!({"subtrajectory": j.subtrajectory}))?,
            ..Default::default()
        };
        joints.push(w.node(node));
    }
    let mut frustums = Vec::with_capacity(plan.frustums.len());
    for (i, f) in plan.frustums.iter().enumerate() {
        let pose = to_gltf(conv, f.pose);
        let mesh = w.mesh(ShapeKind::Frustum, Paint::Frustum);
        let node = json::Node {
            name: Some(format!("frustum_{i}")),
            mesh: Some(mesh),
            translation: Some(vec3(pose.position, "frustum position")?),
            rotation: Some(quat(pose.rotation, "frustum rotation")?),
            extras: extras(serde_json::json!({"subtrajectory": f.subtrajectory}))?,
            ..Default::default()
        };
        frustums.push(w.node(node));
    }
    let mut markers = Vec::with_capacity(parts.markers.len());
    for (i, m) in parts.markers.iter().enumerate() {
        let paint = Paint::Class(m.class);
        let exclamation_mesh = w.mesh(ShapeKind::Exclamation, paint);
        let exclamation = w.node(json::Node {
            name: Some("exclamation".into()),
            mesh: Some(exclamation_mesh),
            rotation: Some(quat(rotation(m.upright), "marker rotation")?),
            ..Default::default()
        });
        let sign_mesh = w.mesh(ShapeKind::WarningSign, paint);
        let sign = w.node(json::Node {
            name: Some("warning_sign".into()),
            mesh: Some(sign_mesh),
            rotation: Some(quat(rotation(m.rotation), "marker rotation")?),
            ..Default::default()
        });
        let normal = point(m.normal);
        let node = json::Node {
            name: Some(format!("marker_{i}")),
            children: Some(vec![exclamation, sign]),
            translation: Some(vec3(point(m.position), "marker position")?),
            extras: extras(serde_json::json!({
                "subtrajectory": m.subtrajectory,
                "class": m.class.name(),
                "error": m.error_m,
                "normal": [normal.x, normal.y, normal.z],
            }))?,
            ..Default::default()
        };
        markers.push(w.node(node));
    }

    let mut top = vec![
        w.group("trajectory", segments),
        w.group("joints", joints),
        w.group("frustums", frustums),
        w.group("markers", markers),
    ];
    for (name, pose, paint) in [
        ("start", plan.start, Paint::Start),
        ("stop", plan.stop, Paint::Stop),
    ] {
        if let Some(pose) = pose {
            let mesh = w.mesh(ShapeKind::Endpoint, paint);
            let node = w.node(json::Node {
                name: Some(name.into()),
                mesh: Some(mesh),
                translation: Some(vec3(point(pose.position), name)?),
                ..Default::default()
            });
            top.push(node);
        }
    }
    if !parts.surface_points.is_empty() {
        let points: Vec<[f32; 3]> = parts
            .surface_points
            .iter()
            .map(|(_, p)| vec3(point(*p), "surface point"))
            .collect::<Result<_, _>>()?;
        let positions = w.vec3_accessor(&points, true);
        let material = w.material(Paint::Surface);
        let mut attributes = BTreeMap::new();
        attributes.insert(Valid(json::mesh::Semantic::Positions), positions);
        let mesh = w.root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: Some("surface_points".into()),
            primitives: vec![json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: None,
                indices: None,
                material: Some(material),
                mode: Valid(json::mesh::Mode::Points),
                targets: None,
            }],
            weights: None,
        });
        let node = w.node(json::Node {
            name: Some("surface_points".into()),
            mesh: Some(mesh),
            ..Default::default()
        });
        top.push(node);
    }
    let root_node = w.node(json::Node {
        name: Some("sitar_session".into()),
        children: Some(top),
        extras: extras(serde_json::json!({"source_convention": conv.name()}))?,
        ..Default::default()
    });
    w.finish(root_node)
}
