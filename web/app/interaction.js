// Left-drag on the surface (docs/web.md, docs/tools.md, docs/haptics.md): picking, the rigid tools (probe
// sphere: press and slide; grasper: close the jaws and pull) and the node pull through the virtual
// coupling; the left-drag mode.
import * as THREE from 'three';
import { $, S, F_MAX, B_VC, TOOL_STEP, GRASP_OPEN_DEG, GRASP_CLOSE_MS, errorText, showError } from './state.js';
import { camera, renderer, mesh, restMesh } from './scene.js';

// ---------------------------------------------------------------- picking and dragging
const raycaster = new THREE.Raycaster();

function ndc(clientX, clientY) {
  const r = renderer.domElement.getBoundingClientRect();
  return new THREE.Vector2(((clientX - r.left) / r.width) * 2 - 1, -((clientY - r.top) / r.height) * 2 + 1);
}

/// The surface node under a client point (nearest corner of the hit triangle), or null.
export function pickAt(clientX, clientY) {
  if (!mesh) return null;
  raycaster.setFromCamera(ndc(clientX, clientY), camera);
  const hit = raycaster.intersectObject(mesh, false)[0];
  if (!hit || !hit.face) return null;
  const P = mesh.geometry.attributes.position.array;
  let best = -1, bestD = Infinity;
  for (const i of [hit.face.a, hit.face.b, hit.face.c]) {
    const d = hit.point.distanceToSquared(new THREE.Vector3(P[3 * i], P[3 * i + 1], P[3 * i + 2]));
    if (d < bestD) { bestD = d; best = i; }
  }
  return { node: best, point: hit.point.clone() };
}

/// Tool sizes for the current model (mm).
export function toolSizes() {
  const radius = Number($('radius').value) * S.size;
  return { radius, depth: Number($('depth').value) * radius, jawRadius: 0.012 * S.size, jawLength: 0.1 * S.size };
}

/// Where a rigid tool aims for a cursor position: its front at `depth` beyond the rest surface along the
/// view ray (sphere: the centre a radius before that point; grasper: the hinge so that the jaw
/// tips reach it). Off the rest surface, the target keeps to the camera-facing plane of the last one.
function toolTarget(clientX, clientY) {
  const d = S.drag;
  raycaster.setFromCamera(ndc(clientX, clientY), camera);
  const dir = raycaster.ray.direction.clone().normalize();
  if (d.mode === 'grasp' && d.closedAt !== undefined) {  // holding: the grasp follows the cursor on its plane
    const p = raycaster.ray.intersectPlane(d.plane, new THREE.Vector3());
    return p ? d.tool0.clone().add(p.sub(d.hit0)) : null;
  }
  const hit = raycaster.intersectObject(restMesh, false)[0];
  let front;
  if (hit) {
    front = hit.point.clone().addScaledVector(dir, d.depth);
  } else {
    const p = raycaster.ray.intersectPlane(d.plane, new THREE.Vector3());
    if (!p) return null;
    front = p;
  }
  d.plane.setFromNormalAndCoplanarPoint(camera.getWorldDirection(new THREE.Vector3()), front);
  return front.addScaledVector(dir, -d.back);
}

export function onPointerDown(ev) {
  if (ev.button !== 0 || !S.engine || S.drag) return;
  const hit = pickAt(ev.clientX, ev.clientY);
  if (!hit) return;  // a drag outside the surface does nothing
  if (S.mode !== 'pull') {
    startTool(ev, hit);
    return;
  }
  try {
    S.engine.grab(hit.node, S.kvc, B_VC, F_MAX);
  } catch (err) {
    showError(`grab: ${errorText(err)}`);
    return;
  }
  const normal = camera.getWorldDirection(new THREE.Vector3());
  S.drag = {
    mode: 'pull',
    node: hit.node,
    pointerId: ev.pointerId,
    plane: new THREE.Plane().setFromNormalAndCoplanarPoint(normal, hit.point),
    hit0: hit.point,
    tool0: new THREE.Vector3().fromArray(S.engine.tool()),
  };
  renderer.domElement.setPointerCapture(ev.pointerId);
  renderer.domElement.style.cursor = 'grabbing';
  ev.preventDefault();
}

/// Probe / grasp: the tool is placed outside the surface on the view ray through the picked point and
/// moves in from there (at most TOOL_STEP x its radius per tick).
function startTool(ev, hit) {
  const sz = toolSizes();
  const dir = hit.point.clone().sub(camera.position).normalize();
  const grasp = S.mode === 'grasp';
  const open = THREE.MathUtils.degToRad(GRASP_OPEN_DEG);
  // sphere: front `depth` beyond the surface, centre r behind it; grasper: jaw tip centres at the surface
  const back = grasp ? sz.jawLength * Math.cos(open / 2) : sz.radius;
  const depth = grasp ? 0 : sz.depth;
  const clearance = grasp ? 1.5 * sz.jawLength + 2 * sz.jawRadius : 1.5 * sz.radius;  // open jaws reach sideways
  const start = hit.point.clone().addScaledVector(dir, -clearance);
  const spec = grasp ? `grasper:${sz.jawRadius}:${sz.jawLength}:${GRASP_OPEN_DEG}` : `sphere:${sz.radius}`;
  const step = TOOL_STEP * (grasp ? sz.jawLength : sz.radius);
  try {
    S.engine.placeTool(spec, start.x, start.y, start.z, dir.x, dir.y, dir.z, Number($('friction').value), F_MAX * 3, step);
  } catch (err) {
    showError(`${S.mode}: ${errorText(err)}`);
    return;
  }
  S.drag = {
    mode: S.mode, pointerId: ev.pointerId, dir, depth, back,
    plane: new THREE.Plane().setFromNormalAndCoplanarPoint(camera.getWorldDirection(new THREE.Vector3()), hit.point),
    hit0: hit.point.clone(),
    downAt: performance.now(),
  };
  const target = toolTarget(ev.clientX, ev.clientY) || hit.point.clone().addScaledVector(dir, depth - back);
  S.drag.target = target;
  S.engine.moveTool(target.x, target.y, target.z);
  renderer.domElement.setPointerCapture(ev.pointerId);
  renderer.domElement.style.cursor = 'grabbing';
  ev.preventDefault();
}

/// Grasp mode, every pump: once the jaws reached the press, they close over GRASP_CLOSE_MS and hold;
/// from then on the cursor drags the held tissue.
export function updateGrasp(now) {
  const d = S.drag;
  if (!d || d.mode !== 'grasp' || !S.engine.hasTool()) return;
  const ts = S.engine.toolState();
  if (d.reachedAt === undefined) {
    const gap = Math.hypot(ts.position[0] - d.target.x, ts.position[1] - d.target.y, ts.position[2] - d.target.z);
    if (gap < 1e-6 * S.size + 1e-9) d.reachedAt = now;
    return;
  }
  const s = Math.min(1, (now - d.reachedAt) / GRASP_CLOSE_MS);
  S.engine.setOpening(GRASP_OPEN_DEG * (1 - s));
  if (s >= 1 && d.closedAt === undefined) {
    d.closedAt = now;
    d.tool0 = new THREE.Vector3().fromArray(ts.position);
    d.hit0 = d.lastPlanePoint ? d.lastPlanePoint.clone() : d.hit0;
    d.plane.setFromNormalAndCoplanarPoint(camera.getWorldDirection(new THREE.Vector3()), d.hit0);
  }
}

export function onPointerMove(ev) {
  if (!S.drag) {  // hover: show whether a press would pick the surface
    if (ev.buttons === 0) renderer.domElement.style.cursor = pickAt(ev.clientX, ev.clientY) ? 'grab' : 'default';
    return;
  }
  if (ev.pointerId !== S.drag.pointerId) return;
  if (S.drag.mode !== 'pull') {
    if (S.drag.mode === 'grasp' && S.drag.closedAt === undefined) {  // before the jaws close: remember where
      raycaster.setFromCamera(ndc(ev.clientX, ev.clientY), camera);
      S.drag.lastPlanePoint = raycaster.ray.intersectPlane(S.drag.plane, new THREE.Vector3()) || S.drag.lastPlanePoint;
      return;
    }
    const t = toolTarget(ev.clientX, ev.clientY);
    if (!t) return;
    S.drag.target = t;
    S.engine.moveTool(t.x, t.y, t.z);
    return;
  }
  raycaster.setFromCamera(ndc(ev.clientX, ev.clientY), camera);
  const p = raycaster.ray.intersectPlane(S.drag.plane, new THREE.Vector3());
  if (!p) return;
  const tool = S.drag.tool0.clone().add(p.sub(S.drag.hit0));
  S.engine.moveTool(tool.x, tool.y, tool.z);
}

export function onPointerUp(ev) {
  if (!S.drag || ev.pointerId !== S.drag.pointerId) return;
  S.drag = null;
  if (S.engine) S.engine.release();
}

export function setMode(m) {
  if (!['probe', 'grasp', 'pull'].includes(m)) throw new Error(`unknown mode '${m}' (probe, grasp or pull)`);
  if (S.drag) { S.drag = null; if (S.engine) S.engine.release(); }
  S.mode = m;
  $('mode').value = m;
}
