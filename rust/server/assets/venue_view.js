// The venue report's 3-D view: the map's cells and every aligned session's path, from the
// page's own `venue-data` (report/venue_view.rs: glTF's frame as map.glb, right-handed,
// +Y up, metres, the anchor at the origin). Drawn as map.glb draws them: surface cells as
// translucent tiles, path cells as small faint boxes, coloured by class.
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { framing } from "./view_framing.js";

// By class code: unknown, low, medium, high (the page's swatches).
const CLASS_COLOURS = [0x9a9a9a, 0x2f6fde, 0xe0b100, 0xd62728];

const $ = (id) => document.getElementById(id);

// One instanced box per cell (centres flat x, y, z), edge `edge` m, coloured by class.
function cellBoxes(centres, classes, edge, opacity) {
  const geometry = new THREE.BoxGeometry(edge, edge, edge);
  const material = new THREE.MeshStandardMaterial({ transparent: true, opacity, depthWrite: false, roughness: 0.8 });
  const mesh = new THREE.InstancedMesh(geometry, material, Math.max(classes.length, 1));
  mesh.count = classes.length;
  const m = new THREE.Matrix4(), c = new THREE.Color();
  for (let i = 0; i < classes.length; i++) {
    m.makeTranslation(centres[3 * i], centres[3 * i + 1], centres[3 * i + 2]);
    mesh.setMatrixAt(i, m);
    mesh.setColorAt(i, c.setHex(CLASS_COLOURS[classes[i]] ?? CLASS_COLOURS[0]));
  }
  return mesh;
}

export async function venueMain(inline) {
  const data = JSON.parse(inline.textContent);
  const status = (text) => ($("view-status").textContent = text);
  const canvas = $("view3d");
  const points = [];
  const push = (flat) => {
    for (let i = 0; i + 2 < flat.length; i += 3) points.push(new THREE.Vector3(flat[i], flat[i + 1], flat[i + 2]));
  };
  push(data.surface.centres);
  push(data.path.centres);
  for (const p of data.paths) push(p);
  points.push(new THREE.Vector3(0, 0, 0));
  if (points.length < 2) {
    status("Nothing to show yet: no aligned session with a finished estimate.");
    document.body.dataset.view = "empty";
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

  const room = new THREE.Box3().setFromPoints(points).expandByScalar(data.cell_m);
  const size = room.getSize(new THREE.Vector3());
  const centre = room.getCenter(new THREE.Vector3());
  const cells = Math.ceil(Math.max(size.x, size.z) + 2);
  const grid = new THREE.GridHelper(cells, cells, 0x999999, 0xd0d0d0);
  grid.position.set(Math.round(centre.x), room.min.y, Math.round(centre.z));
  scene.add(grid);
  scene.add(new THREE.AxesHelper(1));

  const surface = cellBoxes(data.surface.centres, data.surface.classes, data.surface_share * data.cell_m, 0.55);
  const path = cellBoxes(data.path.centres, data.path.classes, data.path_share * data.cell_m, 0.25);
  scene.add(surface, path);
  // The printed anchor: an A4 sheet at the venue origin.
  const anchor = new THREE.Mesh(new THREE.BoxGeometry(0.297, 0.21, 0.005), new THREE.MeshStandardMaterial({ color: 0x111111 }));
  scene.add(anchor);
  const paths = new THREE.Group();
  const line = new THREE.LineBasicMaterial({ color: 0x555555 });
  for (const p of data.paths) {
    if (p.length < 6) continue;
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.Float32BufferAttribute(p, 3));
    paths.add(new THREE.Line(geometry, line));
  }
  scene.add(paths);

  const camera = new THREE.PerspectiveCamera(50, canvas.clientWidth / canvas.clientHeight || 16 / 9, 0.01, 1000);
  camera.updateProjectionMatrix();
  const controls = new OrbitControls(camera, canvas);
  const look = framing(camera, controls, room);
  const home = () => { camera.up.set(0, 1, 0); look(new THREE.Vector3(0.55, 0.6, 0.75).normalize()); };
  const top = () => { camera.up.set(0, 1, 0); look(new THREE.Vector3(0, 1, 1e-3).normalize()); };
  home();
  let pending = false;
  function render() {
    pending = false;
    const w = canvas.clientWidth, h = canvas.clientHeight;
    if (canvas.width !== Math.round(w * renderer.getPixelRatio()) || canvas.height !== Math.round(h * renderer.getPixelRatio())) {
      renderer.setSize(w, h, false);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
    }
    renderer.render(scene, camera);
  }
  const request = () => { if (!pending) { pending = true; requestAnimationFrame(render); } };
  controls.addEventListener("change", request);
  window.addEventListener("resize", request);
  $("btn-top").addEventListener("click", () => { top(); request(); });
  $("btn-reset").addEventListener("click", () => { home(); request(); });
  $("chk-surface").addEventListener("change", (e) => { surface.visible = e.target.checked; request(); });
  $("chk-path").addEventListener("change", (e) => { path.visible = e.target.checked; request(); });
  $("chk-paths").addEventListener("change", (e) => { paths.visible = e.target.checked; request(); });

  // How many of the drawn points the default view shows (tests read it: all of them).
  camera.updateMatrixWorld();
  const inView = points.filter((p) => {
    const q = p.clone().project(camera);
    return Math.abs(q.x) <= 1 && Math.abs(q.y) <= 1 && q.z < 1;
  }).length;
  document.body.dataset.framed = `${inView}/${points.length}`;
  render();
  document.body.dataset.view = "ready";
  const d = data.downsampled;
  const thinned = Object.entries(d).filter(([, c]) => c.shown < c.total).map(([k, c]) => `${c.shown} of ${c.total} ${k}`);
  const count = (n, one) => `${n} ${one}${n === 1 ? "" : "s"}`;
  status(`${count(d.surface_cells.total, "surface cell")}, ${count(d.path_cells.total, "path cell")}, ${count(data.paths.length, "session path")}.` +
    (thinned.length ? ` Drawn thinned for display (${thinned.join(", ")}); the tables on this page are from all of them.` : ""));
}
