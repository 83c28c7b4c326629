// How both 3-D views (a session's walk, a venue's map) frame what they show: the camera
// looks at the centre of `room` (a THREE.Box3) from the nearest distance along a direction
// at which all eight of its corners are in view.
import * as THREE from "three";

export function framing(camera, controls, room) {
  const sphere = room.getBoundingSphere(new THREE.Sphere());
  function distance(dir) {
    const tanV = Math.tan(THREE.MathUtils.degToRad(camera.fov) / 2);
    const tanH = tanV * camera.aspect;
    const right = new THREE.Vector3().crossVectors(camera.up, dir);
    if (right.lengthSq() < 1e-9) right.set(1, 0, 0);
    right.normalize();
    const up = new THREE.Vector3().crossVectors(dir, right).normalize();
    let d = 0.5;
    const c = new THREE.Vector3();
    for (let i = 0; i < 8; i++) {
      c.set(i & 1 ? room.max.x : room.min.x, i & 2 ? room.max.y : room.min.y, i & 4 ? room.max.z : room.min.z).sub(sphere.center);
      const depth = c.dot(dir);
      d = Math.max(d, depth + Math.abs(c.dot(right)) / tanH, depth + Math.abs(c.dot(up)) / tanV);
    }
    return d * 1.04;
  }
  // Looks along -dir at the room from the nearest distance that shows it whole.
  return function look(dir) {
    camera.position.copy(sphere.center).addScaledVector(dir, distance(dir));
    controls.target.copy(sphere.center);
    controls.update();
  };
}
