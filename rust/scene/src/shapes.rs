//! The unit shapes the scene instantiates, in glTF's frame (+Y up, camera looks −Z).

use std::f32::consts::TAU;

/// Triangle geometry with per-vertex normals, or line/point geometry without.
pub(crate) struct Shape {
    pub positions: Vec<[f32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
    pub indices: Vec<u16>,
}

/// Tube radius (metres): thin enough to see the room through the path.
pub(crate) const TUBE_RADIUS: f32 = 0.012;
/// Joint sphere radius (metres): a little wider than the tube so the joints show.
pub(crate) const JOINT_RADIUS: f32 = 0.016;

/// An open cylinder of radius [`TUBE_RADIUS`], height 1 along +Y, centred on the origin:
/// a segment node scales its Y by the segment's length.
pub(crate) fn cylinder() -> Shape {
    const SIDES: u16 = 12;
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for i in 0..SIDES {
        let a = TAU * f32::from(i) / f32::from(SIDES);
        let (s, c) = a.sin_cos();
        for y in [-0.5, 0.5] {
            positions.push([TUBE_RADIUS * c, y, TUBE_RADIUS * s]);
            normals.push([c, 0.0, s]);
        }
    }
    let mut indices = Vec::new();
    for i in 0..SIDES {
        let (a0, a1) = (2 * i, 2 * i + 1);
        let (b0, b1) = (2 * ((i + 1) % SIDES), 2 * ((i + 1) % SIDES) + 1);
        // Counter-clockwise seen from outside.
        indices.extend_from_slice(&[a0, a1, b0, b0, a1, b1]);
    }
    Shape {
        positions,
        normals: Some(normals),
        indices,
    }
}

/// A UV sphere of the given radius centred on the origin.
pub(crate) fn sphere(radius: f32) -> Shape {
    const RINGS: u16 = 6;
    const SEGMENTS: u16 = 10;
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for r in 0..=RINGS {
        let phi = std::f32::consts::PI * f32::from(r) / f32::from(RINGS);
        for s in 0..=SEGMENTS {
            let theta = TAU * f32::from(s) / f32::from(SEGMENTS);
            let n = [phi.sin() * theta.cos(), phi.cos(), phi.sin() * theta.sin()];
            positions.push([n[0] * radius, n[1] * radius, n[2] * radius]);
            normals.push(n);
        }
    }
    let mut indices = Vec::new();
    let row = SEGMENTS + 1;
    for r in 0..RINGS {
        for s in 0..SEGMENTS {
            let a = r * row + s;
            let b = a + row;
            if r != 0 {
                indices.extend_from_slice(&[a, a + 1, b]);
            }
            if r != RINGS - 1 {
                indices.extend_from_slice(&[a + 1, b + 1, b]);
            }
        }
    }
    Shape {
        positions,
        normals: Some(normals),
        indices,
    }
}

/// A camera frustum as lines: apex at the origin, a 12 × 9 cm image plane 15 cm along −Z.
pub(crate) fn frustum() -> Shape {
    let (w, h, d) = (0.06, 0.045, -0.15);
    let positions = vec![
        [0.0, 0.0, 0.0],
        [-w, -h, d],
        [w, -h, d],
        [w, h, d],
        [-w, h, d],
        // The "up" tick above the image plane, so the camera's roll shows.
        [0.0, h * 1.6, d],
    ];
    let indices = vec![0, 1, 0, 2, 0, 3, 0, 4, 1, 2, 2, 3, 3, 4, 4, 1, 3, 5, 5, 4];
    Shape {
        positions,
        normals: None,
        indices,
    }
}

/// An axis-aligned box from `lo` to `hi`, 24 vertices so each face has its own normal.
fn push_box(shape: &mut Shape, lo: [f32; 3], hi: [f32; 3]) {
    let normals = shape.normals.get_or_insert_with(Vec::new);
    for axis in 0..3 {
        for side in [0, 1] {
            let mut n = [0.0f32; 3];
            n[axis] = if side == 1 { 1.0 } else { -1.0 };
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = shape.positions.len() as u16;
            for (du, dv) in [(0, 0), (1, 0), (1, 1), (0, 1)] {
                let mut p = [0.0f32; 3];
                p[axis] = if side == 1 { hi[axis] } else { lo[axis] };
                p[u] = if du == 1 { hi[u] } else { lo[u] };
                p[v] = if dv == 1 { hi[v] } else { lo[v] };
                shape.positions.push(p);
                normals.push(n);
            }
            // (u, v, n) is right-handed, so (0,1,2) winds counter-clockwise seen from +n.
            let quad = if side == 1 {
                [0, 1, 2, 0, 2, 3]
            } else {
                [0, 2, 1, 0, 3, 2]
            };
            shape.indices.extend(quad.iter().map(|i| base + i));
        }
    }
}

/// The exclamation point: a bar and a dot standing on the surface point (upright, +Y).
pub(crate) fn exclamation() -> Shape {
    let mut shape = Shape {
        positions: Vec::new(),
        normals: Some(Vec::new()),
        indices: Vec::new(),
    };
    push_box(&mut shape, [-0.02, 0.10, -0.02], [0.02, 0.34, 0.02]);
    push_box(&mut shape, [-0.02, 0.02, -0.02], [0.02, 0.06, 0.02]);
    shape
}

/// The warning sign: a triangle plate lying on the surface (normal local +Y), its apex up
/// the surface (local +Z in glTF's frame), 1 cm off the surface so it does not flicker.
pub(crate) fn warning_sign() -> Shape {
    let s = 0.15f32;
    let y = 0.01;
    let positions = vec![
        [0.0, y, s],
        [-s * 0.866, y, -s * 0.5],
        [s * 0.866, y, -s * 0.5],
    ];
    Shape {
        normals: Some(vec![[0.0, 1.0, 0.0]; 3]),
        positions,
        // Counter-clockwise seen from +Y.
        indices: vec![0, 2, 1],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(shape: &Shape) {
        let n = shape.positions.len();
        assert!(shape.indices.iter().all(|&i| usize::from(i) < n));
        if let Some(normals) = &shape.normals {
            assert_eq!(normals.len(), n);
            for v in normals {
                let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                assert!((len - 1.0).abs() < 1e-5, "normal {v:?}");
            }
        }
    }

    #[test]
    fn shapes_index_their_own_vertices_with_unit_normals() {
        for shape in [
            cylinder(),
            sphere(JOINT_RADIUS),
            frustum(),
            exclamation(),
            warning_sign(),
        ] {
            check(&shape);
        }
        assert_eq!(cylinder().indices.len() % 3, 0);
        assert_eq!(frustum().indices.len() % 2, 0);
    }

    #[test]
    fn triangles_face_their_normals() {
        // Every triangle's geometric normal points the way its vertex normals do.
        for shape in [cylinder(), sphere(0.5), exclamation(), warning_sign()] {
            let normals = shape.normals.as_ref().unwrap();
            for t in shape.indices.chunks(3) {
                let [a, b, c] = [0, 1, 2].map(|k| shape.positions[usize::from(t[k])]);
                let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
                let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
                let g = [
                    e1[1] * e2[2] - e1[2] * e2[1],
                    e1[2] * e2[0] - e1[0] * e2[2],
                    e1[0] * e2[1] - e1[1] * e2[0],
                ];
                let n = normals[usize::from(t[0])];
                assert!(g[0] * n[0] + g[1] * n[1] + g[2] * n[2] > 0.0, "{t:?}");
            }
        }
    }
}

/// A cube of edge 1 centred on the origin, with flat normals (24 vertices): a venue cell
/// node scales it to its size.
pub(crate) fn cube() -> Shape {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut indices = Vec::new();
    // Each face: its normal axis and sign, and two in-face axes with `u × v = normal`.
    for (axis, sign) in [
        (0, 1.0),
        (0, -1.0),
        (1, 1.0),
        (1, -1.0),
        (2, 1.0),
        (2, -1.0),
    ] {
        let (u_axis, v_axis) = ((axis + 1) % 3, (axis + 2) % 3);
        let base = positions.len() as u16;
        let mut normal = [0.0f32; 3];
        normal[axis] = sign;
        for (a, b) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
            let mut p = [0.0f32; 3];
            p[axis] = 0.5 * sign;
            p[u_axis] = a;
            p[v_axis] = b * sign;
            positions.push(p);
            normals.push(normal);
        }
        // Counter-clockwise seen from outside.
        indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    Shape {
        positions,
        normals: Some(normals),
        indices,
    }
}

#[cfg(test)]
mod cube_tests {
    use super::*;

    /// Every triangle of the cube winds counter-clockwise seen from outside: its geometric
    /// normal points along the vertex normal.
    #[test]
    fn cube_faces_wind_outwards() {
        let c = cube();
        let normals = c.normals.as_ref().unwrap();
        assert_eq!((c.positions.len(), c.indices.len()), (24, 36));
        for t in c.indices.chunks(3) {
            let [a, b, d] = [0, 1, 2].map(|k| c.positions[t[k] as usize]);
            let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let e2 = [d[0] - a[0], d[1] - a[1], d[2] - a[2]];
            let cross = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            let n = normals[t[0] as usize];
            let dot = cross[0] * n[0] + cross[1] * n[1] + cross[2] * n[2];
            assert!(dot > 0.0, "{t:?}");
        }
    }
}
