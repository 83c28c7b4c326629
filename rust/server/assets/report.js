// The report's 3-D view: the walk in the room, from scene.json (glTF's frame: right-handed,
// +Y up, metres). three.js comes from tools/npm (the pinned version); scripts/bundle-report
// bundles the parts used into report.bundle.js, served by this backend, so it works offline.
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { framing } from "./view_framing.js";
import { venueMain } from "./venue_view.js";

const CLASS_COLOURS = { low: 0x2f6fde, medium: 0xe0b100, high: 0xd62728, unknown: 0x9a9a9a };
const VIRIDIS = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];

function viridis(t) {
  const x = Math.min(Math.max(t, 0), 1) * (VIRIDIS.length - 1);
  const i = Math.min(Math.floor(x), VIRIDIS.length - 2);
  const f = x - i;
  const c = VIRIDIS[i].map((v, k) => (v + (VIRIDIS[i + 1][k] - v) * f) / 255);
  return new THREE.Color().setRGB(c[0], c[1], c[2], THREE.SRGBColorSpace);
}

const $ = (id) => document.getElementById(id);

// A tube through `points` as one indexed geometry: a ring of `radial` vertices per point,
// its frame carried along the path (parallel transport), so no curve fitting or arc-length
// sampling is needed. Faces 2·radial per segment, in path order (picking relies on it).
function tubeGeometry(points, radius, radial) {
  const n = points.length;
  const ring = radial + 1;
  const position = new Float32Array(n * ring * 3);
  const normal = new Float32Array(n * ring * 3);
  const index = new Uint32Array((n - 1) * radial * 6);
  const t = new THREE.Vector3(), u = new THREE.Vector3(), v = new THREE.Vector3(), d = new THREE.Vector3();
  for (let i = 0; i < n; i++) {
    t.subVectors(points[Math.min(i + 1, n - 1)], points[Math.max(i - 1, 0)]);
    if (t.lengthSq() < 1e-12) t.set(1, 0, 0);
    t.normalize();
    // Keep the previous ring's normal, less its part along the new tangent.
    if (i === 0 || u.lengthSq() < 1e-12) u.set(0, 1, 0);
    u.addScaledVector(t, -u.dot(t));
    if (u.lengthSq() < 1e-8) u.set(1, 0, 0).addScaledVector(t, -t.x);
    u.normalize();
    v.crossVectors(t, u);
    for (let k = 0; k <= radial; k++) {
      const a = (k / radial) * Math.PI * 2;
      d.copy(u).multiplyScalar(Math.cos(a)).addScaledVector(v, Math.sin(a));
      const o = (i * ring + k) * 3;
      normal[o] = d.x; normal[o + 1] = d.y; normal[o + 2] = d.z;
      position[o] = points[i].x + d.x * radius;
      position[o + 1] = points[i].y + d.y * radius;
      position[o + 2] = points[i].z + d.z * radius;
    }
  }
  let f = 0;
  for (let i = 0; i + 1 < n; i++) {
    for (let k = 0; k < radial; k++) {
      const a = i * ring + k, b = a + ring, c = b + 1, e = a + 1;
      // Counter-clockwise seen from outside: front faces face out.
      index[f++] = a; index[f++] = e; index[f++] = b;
      index[f++] = b; index[f++] = e; index[f++] = c;
    }
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.BufferAttribute(position, 3));
  geometry.setAttribute("normal", new THREE.BufferAttribute(normal, 3));
  geometry.setIndex(new THREE.BufferAttribute(index, 1));
  return geometry;
}

function status(text) {
  $("view-status").textContent = text;
}

async function main() {
  performance.mark("modules-ready");
  const canvas = $("view3d");
  let data;
  // A saved report (`?download=1`, the demo's page) carries its scene inline: no server.
  const inline = document.getElementById("scene-data");
  if (inline) {
    data = JSON.parse(inline.textContent);
    performance.mark("scene-fetched");
    performance.mark("scene-parsed");
  }
  if (!data) try {
    // The owner's page and a share link's fetch the scene from different places.
    const response = await fetch(document.body.dataset.scene);
    performance.mark("scene-fetched");
    if (!response.ok) {
      status("No 3-D scene: " + (await response.text()));
      return;
    }
    data = await response.json();
    performance.mark("scene-parsed");
  } catch (e) {
    status("No 3-D scene: " + e);
    return;
  }
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf4f5f7);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x666666, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 1.2);
  sun.position.set(3, 6, 2);
  scene.add(sun);

  const joints = [];
  for (let i = 0; i + 2 < data.joints.length; i += 3) {
    joints.push(new THREE.Vector3(data.joints[i], data.joints[i + 1], data.joints[i + 2]));
  }
  if (joints.length < 2) {
    status("No trajectory yet.");
    return;
  }
  // The camera frames the walk and what it faced (surface points, markers); sizes of the
  // drawn things follow the walk's own extent.
  const box = new THREE.Box3().setFromPoints(joints);
  const framed = joints.slice();
  for (let i = 0; i + 2 < data.surface.length; i += 3) framed.push(new THREE.Vector3(data.surface[i], data.surface[i + 1], data.surface[i + 2]));
  for (const m of data.markers) framed.push(new THREE.Vector3(...m.p));
  const room = new THREE.Box3().setFromPoints(framed);
  const size = box.getSize(new THREE.Vector3());
  const span = Math.max(size.x, size.z, 1);
  // A marker sign reaches past its point: the frame keeps most of it.
  room.expandByScalar(0.25 * Math.max(1.5, span / 4));

  // Grid (1 m cells) on the floor under the walk, and axes at the origin.
  const floorY = box.min.y - 1.2;
  const roomSize = room.getSize(new THREE.Vector3());
  const roomCentre = room.getCenter(new THREE.Vector3());
  const cells = Math.ceil(Math.max(roomSize.x, roomSize.z, span) + 2);
  const grid = new THREE.GridHelper(cells, cells, 0x999999, 0xd0d0d0);
  grid.position.set(Math.round(roomCentre.x), floorY, Math.round(roomCentre.z));
  scene.add(grid);
  const axes = new THREE.AxesHelper(1);
  axes.position.set(0, floorY, 0);
  scene.add(axes);

  // The tube: one geometry, vertex colours per ring from the sub-trajectory of that point.
  const subOf = data.joint_sub;
  // A long walk's scene.json carries only the sub-trajectories something drawn refers to.
  const columns = data.subs;
  const subs = new Map(columns.index.map((k, i) => [k, {
    t0: columns.t0[i], t1: columns.t1[i], error: columns.error[i], class: columns.class[i], length: columns.length[i],
  }]));
  // One ring per path point (a 10-minute walk logs 3 600; scene.json thins past 6 000).
  const tubular = joints.length - 1;
  const radial = 6;
  const tube = tubeGeometry(joints, 0.012 * Math.max(1, span / 8), radial);
  const ringJoint = joints.map((_, i) => i);
  const colours = new Float32Array((tubular + 1) * (radial + 1) * 3);
  tube.setAttribute("color", new THREE.BufferAttribute(colours, 3));
  const errors = columns.error.filter((e) => e !== null);
  const maxError = Math.max(data.thresholds[1] * 1.2, ...errors);
  function paint(byError) {
    for (let r = 0; r <= tubular; r++) {
      const sub = subs.get(subOf[ringJoint[r]]);
      const c = byError
        ? (sub && sub.error !== null ? viridis(sub.error / maxError) : new THREE.Color(CLASS_COLOURS.unknown))
        : new THREE.Color(CLASS_COLOURS[sub ? sub.class : "unknown"]);
      for (let k = 0; k <= radial; k++) {
        const o = (r * (radial + 1) + k) * 3;
        colours[o] = c.r; colours[o + 1] = c.g; colours[o + 2] = c.b;
      }
    }
    tube.attributes.color.needsUpdate = true;
    $("colourbar").hidden = !byError;
    $("cb-min").textContent = "0 " + data.unit;
    $("cb-max").textContent = maxError.toFixed(1) + " " + data.unit;
  }
  paint(false);
  const tubeMesh = new THREE.Mesh(tube, new THREE.MeshStandardMaterial({ vertexColors: true, roughness: 0.6 }));
  tubeMesh.userData.ringJoint = ringJoint;
  scene.add(tubeMesh);

  // Start and stop.
  const ball = new THREE.SphereGeometry(0.05 * Math.max(1, span / 8), 16, 12);
  for (const [p, colour] of [[data.start, 0x2ca02c], [data.stop, 0x111111]]) {
    if (!p) continue;
    const m = new THREE.Mesh(ball, new THREE.MeshStandardMaterial({ color: colour }));
    m.position.set(p[0], p[1], p[2]);
    scene.add(m);
  }

  // Frustums: apex, a 12 × 9 cm image plane 15 cm along the camera's −Z, and an up tick.
  const corners = [[0, 0, 0], [-0.06, -0.045, -0.15], [0.06, -0.045, -0.15], [0.06, 0.045, -0.15], [-0.06, 0.045, -0.15], [0, 0.072, -0.15]];
  const edges = [0, 1, 0, 2, 0, 3, 0, 4, 1, 2, 2, 3, 3, 4, 4, 1, 3, 5, 5, 4];
  const fr = [];
  const m4 = new THREE.Matrix4();
  for (const f of data.frustums) {
    m4.compose(new THREE.Vector3(...f.p), new THREE.Quaternion(...f.q), new THREE.Vector3(1, 1, 1));
    for (const e of edges) fr.push(new THREE.Vector3(...corners[e]).applyMatrix4(m4));
  }
  const frustums = new THREE.LineSegments(new THREE.BufferGeometry().setFromPoints(fr), new THREE.LineBasicMaterial({ color: 0x555555 }));
  scene.add(frustums);

  // Surface points the depth samples hit, each with a 30 cm patch of the surface it lies
  // on (square, across its normal): the faced walls, floor and objects, seen in 3-D.
  const surface = new THREE.Group();
  const surfaceGeometry = new THREE.BufferGeometry();
  surfaceGeometry.setAttribute("position", new THREE.Float32BufferAttribute(data.surface, 3));
  surface.add(new THREE.Points(surfaceGeometry, new THREE.PointsMaterial({ color: 0x8c564b, size: 0.05, sizeAttenuation: true })));
  const normals = data.surface_normals || [];
  const patches = [];
  const half = 0.15, nrm = new THREE.Vector3(), a = new THREE.Vector3(), b = new THREE.Vector3();
  for (let i = 0; i + 2 < normals.length && i + 2 < data.surface.length; i += 3) {
    nrm.set(normals[i], normals[i + 1], normals[i + 2]);
    if (nrm.lengthSq() < 1e-6) continue;
    nrm.normalize();
    a.set(0, 1, 0);
    if (Math.abs(nrm.y) > 0.9) a.set(1, 0, 0);
    a.cross(nrm).normalize().multiplyScalar(half);
    b.crossVectors(nrm, a).normalize().multiplyScalar(half);
    const p = new THREE.Vector3(data.surface[i], data.surface[i + 1], data.surface[i + 2]);
    const c = [p.clone().add(a).add(b), p.clone().add(a).sub(b), p.clone().sub(a).sub(b), p.clone().sub(a).add(b)];
    patches.push(c[0], c[1], c[2], c[0], c[2], c[3]);
  }
  if (patches.length) {
    const patchGeometry = new THREE.BufferGeometry().setFromPoints(patches);
    surface.add(new THREE.Mesh(patchGeometry, new THREE.MeshBasicMaterial({
      color: 0xb08d7a, transparent: true, opacity: 0.35, side: THREE.DoubleSide, depthWrite: false })));
  }
  scene.add(surface);

  // Markers: a warning sign on the surface (local +Y = normal) and an upright exclamation point.
  const signShape = new THREE.BufferGeometry().setFromPoints([
    new THREE.Vector3(0, 0.01, 0.15), new THREE.Vector3(0.13, 0.01, -0.075), new THREE.Vector3(-0.13, 0.01, -0.075)]);
  signShape.computeVertexNormals();
  const bar = new THREE.BoxGeometry(0.04, 0.24, 0.04).translate(0, 0.22, 0);
  const dot = new THREE.BoxGeometry(0.04, 0.04, 0.04).translate(0, 0.04, 0);
  const signs = new THREE.Group(), exclamations = new THREE.Group();
  const pickable = [tubeMesh];
  for (const m of data.markers) {
    const material = new THREE.MeshStandardMaterial({ color: CLASS_COLOURS[m.class], side: THREE.DoubleSide });
    const grow = Math.max(1.5, span / 4);
    const sign = new THREE.Mesh(signShape, material);
    sign.position.set(...m.p);
    sign.quaternion.set(...m.q);
    sign.scale.setScalar(grow);
    sign.userData.marker = m;
    signs.add(sign);
    const ex = new THREE.Group();
    ex.add(new THREE.Mesh(bar, material), new THREE.Mesh(dot, material));
    ex.position.set(...m.p);
    ex.scale.setScalar(grow);
    ex.children.forEach((c) => (c.userData.marker = m));
    exclamations.add(ex);
    // The normal, as a short line.
    const n = new THREE.Vector3(...m.normal).multiplyScalar(0.3).add(new THREE.Vector3(...m.p));
    signs.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(...m.p), n]), new THREE.LineBasicMaterial({ color: 0x000000 })));
  }
  scene.add(signs, exclamations);
  pickable.push(signs, exclamations);
  function markerStyle(style) {
    signs.visible = style !== "exclamation";
    exclamations.visible = style !== "sign";
  }
  markerStyle("sign");

  // Camera and controls.
  const camera = new THREE.PerspectiveCamera(50, canvas.clientWidth / canvas.clientHeight || 16 / 9, 0.01, 500);
  camera.updateProjectionMatrix();
  const controls = new OrbitControls(camera, canvas);
  const look = framing(camera, controls, room);
  function home() {
    camera.up.set(0, 1, 0);
    look(new THREE.Vector3(0.55, 0.6, 0.75).normalize());
  }
  function top() {
    camera.up.set(0, 1, 0);
    look(new THREE.Vector3(0, 1, 1e-3).normalize());
  }
  home();

  function resize() {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    if (canvas.width !== Math.round(w * renderer.getPixelRatio()) || canvas.height !== Math.round(h * renderer.getPixelRatio())) {
      renderer.setSize(w, h, false);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
    }
  }
  let pending = false;
  function render() {
    pending = false;
    resize();
    renderer.render(scene, camera);
  }
  function request() {
    if (!pending) { pending = true; requestAnimationFrame(render); }
  }
  controls.addEventListener("change", request);
  window.addEventListener("resize", request);

  $("btn-top").addEventListener("click", () => { top(); request(); });
  $("btn-reset").addEventListener("click", () => { home(); request(); });
  $("chk-error").addEventListener("change", (e) => { paint(e.target.checked); request(); });
  $("sel-markers").addEventListener("change", (e) => { markerStyle(e.target.value); request(); });
  $("chk-frustums").addEventListener("change", (e) => { frustums.visible = e.target.checked; request(); });
  $("chk-surface").addEventListener("change", (e) => { surface.visible = e.target.checked; request(); });

  // Click: the sub-trajectory or marker under the pointer.
  const ray = new THREE.Raycaster();
  let down = null;
  canvas.addEventListener("pointerdown", (e) => (down = [e.clientX, e.clientY]));
  canvas.addEventListener("pointerup", (e) => {
    if (!down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 4) return;
    const rect = canvas.getBoundingClientRect();
    ray.setFromCamera(new THREE.Vector2(((e.clientX - rect.left) / rect.width) * 2 - 1, -((e.clientY - rect.top) / rect.height) * 2 + 1), camera);
    const hit = ray.intersectObjects(pickable, true).find((h) => h.object.userData.marker || h.object === tubeMesh);
    if (!hit) return;
    const m = hit.object.userData.marker;
    if (m) {
      $("picked").textContent = `Marker M${m.number}: sub-trajectory ${m.sub}, ${m.class}, error ${m.error.toFixed(1)} ${data.unit}` +
        (m.tier === undefined || m.tier === null ? "" : `, placed at the ≥ ${m.tier} ${data.unit} tier`);
    } else {
      const ring = Math.floor(hit.faceIndex / (2 * radial));
      const k = subOf[ringJoint[Math.min(ring, ringJoint.length - 1)]];
      const s = subs.get(k);
      $("picked").textContent = s
        ? `Sub-trajectory ${k}: ${s.t0.toFixed(2)}–${s.t1.toFixed(2)} s, ${s.length.toFixed(2)} m, ` +
          (s.error === null ? "no estimate" : `error ${s.error.toFixed(1)} ${data.unit} (${s.class})`)
        : `Sub-trajectory ${k}`;
    }
  });
  // How many of the framed points (path, markers, surface points) the default view shows
  // (tests read it: all of them).
  camera.updateMatrixWorld();
  const inView = framed.filter((p) => {
    const q = p.clone().project(camera);
    return Math.abs(q.x) <= 1 && Math.abs(q.y) <= 1 && q.z < 1;
  }).length;
  document.body.dataset.framed = `${inView}/${framed.length}`;
  performance.mark("scene-built");
  render();
  performance.mark("first-frame");
  document.body.dataset.view = "ready";
  // Where the time went (scripts/bench-report prints these): milliseconds since navigation.
  document.body.dataset.marks = ["modules-ready", "scene-fetched", "scene-parsed", "scene-built", "first-frame"]
    .map((name) => `${name}=${Math.round(performance.getEntriesByName(name)[0].startTime)}`)
    .join(" ");
  // Navigation start to the first frame of the 3-D view (scripts/bench-report reads it).
  document.body.dataset.renderMs = String(Math.round(performance.now()));
  // scripts/bench-report opens the page with #bench: a request marks the first frame in
  // Chromium's net log, on the real clock (headless virtual time also drives performance.now).
  if (location.hash === "#bench") fetch("/healthz?rendered").catch(() => {});
  const d = data.downsampled;
  const thinned = Object.entries(d).filter(([, c]) => c.shown < c.total).map(([k, c]) => `${c.shown} of ${c.total} ${k}`);
  status(`${d.subs.total} sub-trajectories, ${d.frustums.total} frustums, ${d.markers.total} markers, ${d.surface.total} surface points.` +
    (thinned.length ? ` A long walk: drawn thinned for display (${thinned.join(", ")}); the numbers on this page are from all the data.` : ""));
}

// The venue page carries its map inline (`venue-data`); a session's page fetches its scene.
const venueData = document.getElementById("venue-data");
(venueData ? venueMain(venueData) : main()).catch((e) => {
  status("3-D view failed: " + e);
  console.error(e);
});
