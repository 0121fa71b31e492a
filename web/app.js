// MedSpring in the browser (docs/web.md): the C++ engine as WebAssembly (dist/medspring.mjs), a three.js
// view, and a fixed 1 ms physics tick caught up against the wall clock; every animation frame renders the
// surface of the last tick. Left-drag on the surface presses and slides a rigid spherical probe (the
// default; docs/tools.md), closes a grasper's jaws on the surface and pulls, or pulls the picked node
// through a virtual-coupling spring (docs/haptics.md); the arrow is the force on the tissue. Tests drive
// the page through window.medspring.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const TICK_MS = 1;            // physics tick (two 0.5 ms updates of the engine)
const MAX_CATCHUP_TICKS = 100; // at most this many ticks per pump; a longer lag is dropped
const F_MAX = 3;              // N, device maximum of the coupling force
const B_VC = 0.01;            // N ms/mm, coupling damping
const K_VC0 = 0.1;            // N/mm, default coupling stiffness
const TOOL_STEP = 0.05;       // a rigid tool moves at most this x its radius per 1 ms tick towards the cursor
const GRASP_OPEN_DEG = 60;    // grasper: jaws open while approaching
const GRASP_CLOSE_MS = 250;   // then close over this time once the press is reached
const BUILTINS = [
  { id: 'builtin:kidney_phantom', builtin: 'kidney_phantom', name: 'Kidney phantom (built-in)', kind: 'hybrid',
    description: 'Procedural kidney (§4.1): hybrid, 458 surface nodes + 42 atoms' },
  { id: 'builtin:vessel_phantom', builtin: 'vessel_phantom', name: 'Vessel phantom (built-in)', kind: 'smrm',
    description: 'Straight procedural vessel: SMRM, 40 atoms x 30 spokes' },
  { id: 'builtin:tube', builtin: 'tube', name: 'Mass-spring tube (built-in)', kind: 'surface',
    description: 'Plain surface mass-spring tube: 40 rings x 30 nodes' },
];

const $ = (id) => document.getElementById(id);
const errorText = (err) => (err && err.message ? err.message : String(err));

// ---------------------------------------------------------------- state
const S = {
  ms: null,           // the wasm module
  engine: null,       // the current ms.Engine
  model: null,        // its entry of S.models
  models: [],         // {id, name, kind, description, file | builtin}
  defaults: null,     // the model's tissue parameters as loaded
  pendingParams: null,
  drag: null,         // {mode, node, plane, hit0, tool0, ...} while the left button holds the tool
  mode: 'probe',      // left-drag: 'probe' (sphere), 'grasp' (grasper), 'pull' (node coupling)
  kvc: K_VC0,
  ticks: 0, dropped: 0,
  pending: 0,         // ms of wall clock not yet simulated
  batches: [],        // [performance.now(), ticks, wall ms] of the pumps of the last second
  frameTimes: [],
  renderMs: [],       // main-thread ms of the recent frames (geometry upload + render calls)
  forces: [],         // [time, |F|] of the frames of the last 5 s
  error: '', message: '', messageUntil: 0,
  dispScale: 1,
  loading: false,
};

// ---------------------------------------------------------------- three.js scene
let renderer, scene, camera, controls, mesh, restMesh, centerline, atoms, spokes, arrow, spring, toolDot, probeMesh, jaws;

function makeScene() {
  const view = $('view');
  const params = new URLSearchParams(location.search);
  renderer = new THREE.WebGLRenderer({ antialias: params.get('antialias') !== '0' });
  renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
  renderer.setClearColor(0x1d2229);
  view.appendChild(renderer.domElement);
  scene = new THREE.Scene();
  camera = new THREE.PerspectiveCamera(40, 1, 0.1, 1e5);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 1.2));
  const key = new THREE.DirectionalLight(0xffffff, 1.6);
  key.position.set(0.4, 0.7, 1);
  camera.add(key);
  scene.add(camera);
  controls = new OrbitControls(camera, renderer.domElement);
  controls.mouseButtons = { LEFT: null, MIDDLE: THREE.MOUSE.DOLLY, RIGHT: THREE.MOUSE.ROTATE };
  controls.enableDamping = false;

  const arrowColor = 0xffd24a;
  arrow = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 1, arrowColor);
  arrow.visible = false;
  scene.add(arrow);
  spring = new THREE.Line(new THREE.BufferGeometry().setAttribute('position',
    new THREE.Float32BufferAttribute(new Float32Array(6), 3)), new THREE.LineDashedMaterial({ color: 0xffffff, dashSize: 1, gapSize: 0.7 }));
  spring.visible = false;
  scene.add(spring);
  toolDot = new THREE.Mesh(new THREE.SphereGeometry(1, 16, 12), new THREE.MeshBasicMaterial({ color: arrowColor }));
  toolDot.visible = false;
  scene.add(toolDot);
  probeMesh = new THREE.Mesh(new THREE.SphereGeometry(1, 32, 24),
    new THREE.MeshPhongMaterial({ color: 0xc9d1d9, transparent: true, opacity: 0.55, shininess: 80 }));
  probeMesh.visible = false;
  scene.add(probeMesh);
  jaws = new THREE.Group();
  for (let j = 0; j < 2; ++j) {
    const jaw = new THREE.Mesh(new THREE.CylinderGeometry(1, 1, 1, 12), new THREE.MeshPhongMaterial({ color: 0xc9d1d9, shininess: 80 }));
    jaws.add(jaw);
  }
  jaws.visible = false;
  scene.add(jaws);
  new ResizeObserver(resize).observe(view);
  resize();
}

function resize() {
  const view = $('view');
  const w = Math.max(1, view.clientWidth), h = Math.max(1, view.clientHeight);
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
}

function disposeModelObjects() {
  for (const o of [mesh, restMesh, centerline, atoms, spokes]) {
    if (!o) continue;
    scene.remove(o);
    o.geometry.dispose();
    o.material.dispose();
  }
  mesh = restMesh = centerline = atoms = spokes = null;
}

// Builds the three.js objects of the current engine and frames the camera on it.
function buildModelObjects() {
  disposeModelObjects();
  const e = S.engine;
  const n = e.numSurfaceNodes();
  const geo = new THREE.BufferGeometry();
  geo.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * n), 3).setUsage(THREE.DynamicDrawUsage));
  geo.setAttribute('color', new THREE.BufferAttribute(new Float32Array(3 * n), 3).setUsage(THREE.DynamicDrawUsage));
  geo.setIndex(new THREE.BufferAttribute(new Uint32Array(e.faces()), 1));
  mesh = new THREE.Mesh(geo, new THREE.MeshPhongMaterial({ vertexColors: true, side: THREE.DoubleSide, shininess: 40 }));
  scene.add(mesh);
  // The rest surface (never drawn): a rigid tool aims at it, so a dent under the tool does not pull the
  // cursor's target deeper.
  const rg = new THREE.BufferGeometry();
  rg.setAttribute('position', new THREE.BufferAttribute(new Float32Array(e.restPositions()), 3));
  rg.setIndex(new THREE.BufferAttribute(new Uint32Array(e.faces()), 1));
  rg.computeBoundingSphere();
  restMesh = new THREE.Mesh(rg, new THREE.MeshBasicMaterial({ side: THREE.DoubleSide }));

  const na = e.numAtoms();
  const cg = new THREE.BufferGeometry();
  cg.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * Math.max(na, 1)), 3).setUsage(THREE.DynamicDrawUsage));
  cg.setDrawRange(0, na);
  const ag = cg.clone();
  // The centerline's segments (atom pairs): a vessel tree's branches meet at shared junction atoms.
  const edges = new Uint32Array(e.centerlineEdges());
  const lineMaterial = new THREE.LineBasicMaterial({ color: 0x7ee787, depthTest: false });
  if (edges.length > 0) {
    cg.setIndex(new THREE.BufferAttribute(edges, 1));
    cg.setDrawRange(0, edges.length);
    centerline = new THREE.LineSegments(cg, lineMaterial);
  } else {
    centerline = new THREE.Line(cg, lineMaterial);
  }
  centerline.renderOrder = 2;
  atoms = new THREE.Points(ag, new THREE.PointsMaterial({ color: 0xff7b72, size: 7, sizeAttenuation: false, depthTest: false }));
  atoms.renderOrder = 3;
  const pairs = e.spokes();
  const sg = new THREE.BufferGeometry();
  sg.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * Math.max(pairs.length, 2)), 3).setUsage(THREE.DynamicDrawUsage));
  sg.setDrawRange(0, pairs.length);
  spokes = new THREE.LineSegments(sg, new THREE.LineBasicMaterial({ color: 0x79c0ff, transparent: true, opacity: 0.55, depthTest: false }));
  spokes.renderOrder = 1;
  S.spokePairs = new Uint32Array(pairs);
  scene.add(centerline, atoms, spokes);
  for (const id of ['show-centerline', 'show-atoms', 'show-spokes']) $(id).disabled = na === 0;

  const rest = e.restPositions();
  const box = new THREE.Box3();
  const v = new THREE.Vector3();
  for (let i = 0; i < n; ++i) box.expandByPoint(v.fromArray(rest, 3 * i));
  const sphere = box.getBoundingSphere(new THREE.Sphere());
  S.size = e.size();
  S.dispScale = Math.max(0.5, 0.08 * S.size);
  $('legend-max').textContent = `${S.dispScale.toPrecision(2)} mm`;
  const dist = (sphere.radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2))) * 1.05;
  camera.near = dist / 100;
  camera.far = dist * 100;
  camera.position.copy(sphere.center).add(new THREE.Vector3(0, 0, dist));
  camera.up.set(0, 1, 0);
  controls.target.copy(sphere.center);
  camera.updateProjectionMatrix();
  controls.update();
  const r = 0.012 * S.size;
  toolDot.scale.setScalar(r);
  arrow.setLength(1, 0.1 * S.size * 0.5, 0.05 * S.size * 0.5);
  spring.material.dashSize = 0.01 * S.size;
  spring.material.gapSize = 0.007 * S.size;
  refreshGeometry();
}

// Colour map for |displacement| / scale in [0, 1]: blue - light grey - red.
function colormap(t, out, k) {
  t = Math.min(1, Math.max(0, t));
  const a = [0.23, 0.30, 0.75], m = [0.87, 0.87, 0.87], b = [0.71, 0.02, 0.15];
  const [p, q, s] = t < 0.5 ? [a, m, 2 * t] : [m, b, 2 * t - 1];
  for (let c = 0; c < 3; ++c) out[k + c] = p[c] + (q[c] - p[c]) * s;
}

// Copies the engine's surface (after the last tick) into the GPU buffers.
function refreshGeometry() {
  const e = S.engine;
  const P = e.positions(), R = e.restPositions();
  const pos = mesh.geometry.attributes.position, col = mesh.geometry.attributes.color;
  pos.array.set(P);
  const n = P.length / 3, inv = 1 / S.dispScale;
  for (let i = 0; i < n; ++i) {
    const dx = P[3 * i] - R[3 * i], dy = P[3 * i + 1] - R[3 * i + 1], dz = P[3 * i + 2] - R[3 * i + 2];
    colormap(Math.sqrt(dx * dx + dy * dy + dz * dz) * inv, col.array, 3 * i);
  }
  pos.needsUpdate = true;
  col.needsUpdate = true;
  mesh.geometry.computeVertexNormals();
  mesh.geometry.computeBoundingSphere();  // the raycaster culls against it

  const showC = $('show-centerline').checked, showA = $('show-atoms').checked, showS = $('show-spokes').checked;
  const na = e.numAtoms();
  centerline.visible = showC && na > 0;
  atoms.visible = showA && na > 0;
  spokes.visible = showS && na > 0;
  if (na > 0 && (showC || showA || showS)) {
    const A = e.atoms();
    if (showC || showA) {
      centerline.geometry.attributes.position.array.set(A);
      centerline.geometry.attributes.position.needsUpdate = true;
      atoms.geometry.attributes.position.array.set(A);
      atoms.geometry.attributes.position.needsUpdate = true;
      atoms.geometry.setDrawRange(0, na);
    }
    if (showS) {
      const out = spokes.geometry.attributes.position.array, pr = S.spokePairs;
      for (let k = 0; k < pr.length; k += 2) {
        const s = 3 * pr[k], a = 3 * pr[k + 1];
        out[3 * k] = P[s]; out[3 * k + 1] = P[s + 1]; out[3 * k + 2] = P[s + 2];
        out[3 * k + 3] = A[a]; out[3 * k + 4] = A[a + 1]; out[3 * k + 5] = A[a + 2];
      }
      spokes.geometry.attributes.position.needsUpdate = true;
    }
  }

  // The tool: spring from the contact node to the tool, arrow = force on the tissue F = -reaction.
  const grabbed = e.grabbed();
  arrow.visible = spring.visible = toolDot.visible = grabbed;
  const ts = e.toolState();
  probeMesh.visible = !!ts && ts.kind === 'sphere';
  jaws.visible = !!ts && ts.kind === 'grasper';
  if (ts) drawTool(ts);
  if (grabbed) {
    const c = e.contact();
    const x = new THREE.Vector3(P[3 * c], P[3 * c + 1], P[3 * c + 2]);
    const t = new THREE.Vector3().fromArray(e.tool());
    const F = new THREE.Vector3().fromArray(e.reaction()).negate();
    const f = F.length();
    toolDot.position.copy(t);
    const sp = spring.geometry.attributes.position;
    x.toArray(sp.array, 0);
    t.toArray(sp.array, 3);
    sp.needsUpdate = true;
    spring.computeLineDistances();
    if (f > 1e-9) {
      arrow.position.copy(x);
      arrow.setDirection(F.clone().divideScalar(f));
      const len = Math.max(0.02 * S.size, f * 0.25 * S.size);
      arrow.setLength(len, Math.min(0.3 * len, 0.05 * S.size), Math.min(0.15 * len, 0.025 * S.size));
    } else {
      arrow.visible = false;
    }
  }
}

// A rigid tool as the engine has it: the sphere, or the grasper's two jaws about their hinge; the arrow
// is the force on the tissue (-reaction) from the tool's position.
function drawTool(ts) {
  const p = new THREE.Vector3().fromArray(ts.position), axis = new THREE.Vector3().fromArray(ts.axis);
  if (ts.kind === 'sphere') {
    probeMesh.position.copy(p);
    probeMesh.scale.setScalar(ts.radius);
  } else {
    // jaws run from the hinge along axis rotated by +-opening/2 about the jaw plane's normal
    const q = new THREE.Quaternion().setFromUnitVectors(new THREE.Vector3(0, 0, -1), axis);
    const half = THREE.MathUtils.degToRad(ts.opening) / 2;
    jaws.children.forEach((jaw, j) => {
      const s = j ? -1 : 1;
      const dir = new THREE.Vector3(s * Math.sin(half), 0, -Math.cos(half)).applyQuaternion(q);
      jaw.position.copy(p).addScaledVector(dir, ts.length / 2);
      jaw.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), dir);
      jaw.scale.set(ts.radius, ts.length, ts.radius);  // unit cylinder along y
    });
  }
  const F = new THREE.Vector3().fromArray(ts.force).negate();
  const f = F.length();
  arrow.visible = f > 1e-9;
  if (arrow.visible) {
    arrow.position.copy(p);
    arrow.setDirection(F.clone().divideScalar(f));
    const len = Math.max(0.02 * S.size, f * 0.25 * S.size);
    arrow.setLength(len, Math.min(0.3 * len, 0.05 * S.size), Math.min(0.15 * len, 0.025 * S.size));
  }
}

// ---------------------------------------------------------------- picking and dragging
const raycaster = new THREE.Raycaster();

function ndc(clientX, clientY) {
  const r = renderer.domElement.getBoundingClientRect();
  return new THREE.Vector2(((clientX - r.left) / r.width) * 2 - 1, -((clientY - r.top) / r.height) * 2 + 1);
}

/// The surface node under a client point (nearest corner of the hit triangle), or null.
function pickAt(clientX, clientY) {
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
function toolSizes() {
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

function onPointerDown(ev) {
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
function updateGrasp(now) {
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

function onPointerMove(ev) {
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

function onPointerUp(ev) {
  if (!S.drag || ev.pointerId !== S.drag.pointerId) return;
  S.drag = null;
  if (S.engine) S.engine.release();
}

// ---------------------------------------------------------------- UI
function showError(text) {
  S.error = text;
  const e = $('error');
  e.textContent = text;
  e.hidden = !text;
  if (text) console.error(text);
}

function showMessage(text, ms = 4000) {
  S.message = text;
  S.messageUntil = performance.now() + ms;
  $('message').textContent = text;
  $('message').hidden = false;
}

const logSlider = (id, base) => base * Math.pow(10, Number($(id).value));
function sliderParams() {
  const d = S.defaults;
  return {
    k: logSlider('k', d.k),
    eta: Number($('eta').value),
    kr: logSlider('kr', d.kr > 0 ? d.kr : 0.02),
    beta: logSlider('beta', d.beta > 0 ? d.beta : 0.5),
    nonlinear: $('nonlinear').checked,
  };
}
function showParamValues(p) {
  $('k-val').textContent = `${p.k.toPrecision(3)} N/mm`;
  $('eta-val').textContent = p.eta.toFixed(2);
  $('kr-val').textContent = `${p.kr.toPrecision(3)} N/mm`;
  $('beta-val').textContent = `${p.beta.toPrecision(3)} /ms`;
  $('kvc-val').textContent = `${S.kvc.toPrecision(3)} N/mm`;
}
function setSlidersTo(p) {
  const d = S.defaults;
  $('k').value = Math.log10(p.k / d.k);
  $('eta').value = p.eta;
  $('kr').value = Math.log10(p.kr / (d.kr > 0 ? d.kr : 0.02)) || 0;
  $('beta').value = Math.log10(p.beta / (d.beta > 0 ? d.beta : 0.5)) || 0;
  $('nonlinear').checked = p.nonlinear;
  showParamValues(p);
}

function onParamInput() {
  if (!S.engine) return;
  S.pendingParams = sliderParams();
  showParamValues(S.pendingParams);
}

function applyPendingParams() {
  if (!S.pendingParams) return;
  const p = S.pendingParams;
  S.pendingParams = null;
  try {
    S.engine.setParams(p);
    if (S.drag && S.drag.mode !== 'pull') S.drag = null;  // the rebuilt engine removed the rigid tool
    if (S.error.startsWith('Parameters:')) showError('');
  } catch (err) {
    showError(`Parameters: ${errorText(err)}`);
  }
}

function fillModelSelect() {
  const sel = $('model');
  sel.innerHTML = '';
  const groups = new Map();
  for (const m of S.models) {
    const g = m.builtin ? 'built-in' : 'model files';
    if (!groups.has(g)) {
      const og = document.createElement('optgroup');
      og.label = g;
      groups.set(g, og);
      sel.appendChild(og);
    }
    const o = document.createElement('option');
    o.value = m.id;
    o.textContent = m.name;
    groups.get(g).appendChild(o);
  }
}

// models/models.json from `medspring export --web` (an array, or {models: [...]}); the built-in phantoms
// are always offered too, and are all there is when the list is missing.
async function loadModelList() {
  let list = [];
  try {
    const res = await fetch('models/models.json', { cache: 'no-store' });
    if (res.ok) {
      const j = await res.json();
      const arr = Array.isArray(j) ? j : j.models;
      if (!Array.isArray(arr)) throw new Error('models.json: expected a list of models');
      list = arr.filter((m) => m && typeof m.file === 'string').map((m) => ({
        id: m.file, file: m.file, name: m.name || m.file, kind: m.kind || '', description: m.description || '',
      }));
    }
  } catch (err) {
    showError(`Could not read models/models.json: ${errorText(err)} (built-in models only)`);
  }
  S.models = [...list, ...BUILTINS];
  fillModelSelect();
}

/// Loads a model by id (a models.json file or builtin:NAME). On failure the page keeps (or falls back
/// to) a working model and shows the error; returns whether the requested model loaded.
async function loadModel(id) {
  const entry = S.models.find((m) => m.id === id);
  if (!entry) {
    showError(`Unknown model '${id}'`);
    return false;
  }
  S.loading = true;
  let engine = null;
  try {
    if (entry.builtin) {
      engine = new S.ms.Engine(entry.builtin, $('nonlinear').checked, $('local').checked);
    } else {
      const url = `models/${entry.file.split('/').map(encodeURIComponent).join('/')}`;
      const res = await fetch(url, { cache: 'no-store' });
      if (!res.ok) throw new Error(`${url}: HTTP ${res.status} ${res.statusText}`);
      const bytes = new Uint8Array(await res.arrayBuffer());
      engine = new S.ms.Engine(bytes, $('nonlinear').checked, $('local').checked);
    }
  } catch (err) {
    S.loading = false;
    const where = entry.file ? `models/${entry.file}` : entry.builtin;
    const text = `Could not load the model "${entry.name}" (${where}): ${errorText(err)}`;
    // Never a blank canvas: without a running model, fall back to the kidney phantom.
    if (!S.engine && entry.id !== BUILTINS[0].id) await loadModel(BUILTINS[0].id);
    showError(text);
    if (S.model) $('model').value = S.model.id;
    return false;
  }
  if (S.drag) S.drag = null;
  if (S.engine) S.engine.delete();
  S.engine = engine;
  S.model = entry;
  S.defaults = engine.params();
  S.kvc = K_VC0;
  $('kvc').value = 0;
  setSlidersTo(S.defaults);
  $('model').value = entry.id;
  $('model-desc').textContent =
    `${entry.description || engine.description()} — ${engine.numSurfaceNodes()} surface nodes, ` +
    `${engine.numMasses()} masses, ${engine.numSprings()} springs`;
  buildModelObjects();
  showToolValues();
  showError('');
  // a notice about the previous model (a divergence reset) does not carry over to this one
  $('message').hidden = true;
  S.messageUntil = 0;
  S.ticks = 0;
  S.batches = [];
  S.forces = [];
  S.pending = 0;
  S.last = performance.now();
  S.loading = false;
  return true;
}

// ---------------------------------------------------------------- the loop
// Physics: fixed 1 ms ticks caught up against the wall clock by a pump that runs every millisecond or so
// (setInterval; the browser clamps it to ~1-4 ms) and before every frame, independently of the frame
// rate; a lag of more than MAX_CATCHUP_TICKS (a stalled tab, a slow frame) is dropped, not replayed.
// Rendering: every animation frame draws the surface after the last tick.
function pump() {
  const now = performance.now();
  if (!S.engine || S.loading || S.paused) { S.last = now; return; }
  applyPendingParams();
  S.pending += Math.max(0, now - (S.last ?? now));
  S.last = now;
  let n = Math.floor(S.pending / TICK_MS);
  if (n > MAX_CATCHUP_TICKS) {
    S.dropped += n - MAX_CATCHUP_TICKS;
    n = MAX_CATCHUP_TICKS;
    S.pending = 0;
  } else {
    S.pending -= n * TICK_MS;
  }
  if (n <= 0) return;
  const e = S.engine;
  updateGrasp(now);
  const t0 = performance.now();
  e.ticks(n);
  const wall = performance.now() - t0;
  S.ticks += n;
  S.batches.push([now, n, wall]);
  while (S.batches.length && now - S.batches[0][0] > 1000) S.batches.shift();
  const msg = e.message();
  if (msg) {
    e.clearMessage();
    if (S.drag) S.drag = null;
    showMessage(`${msg} (${e.autoResets()} automatic reset${e.autoResets() === 1 ? '' : 's'})`);
  }
}

function frame(now) {
  requestAnimationFrame(frame);
  if (!S.engine || S.loading) return;
  pump();
  if (S.messageUntil && now > S.messageUntil) { $('message').hidden = true; S.messageUntil = 0; }
  S.frameTimes.push(now);
  while (S.frameTimes.length && now - S.frameTimes[0] > 1000) S.frameTimes.shift();
  const F = S.engine.reaction();
  S.forces.push([now, Math.hypot(F[0], F[1], F[2])]);
  while (S.forces.length && now - S.forces[0][0] > 5000) S.forces.shift();
  const r0 = performance.now();
  refreshGeometry();
  controls.update();
  renderer.render(scene, camera);
  S.renderMs.push(performance.now() - r0);
  if (S.renderMs.length > 60) S.renderMs.shift();
  if (now - (S.overlayAt || 0) > 100) { S.overlayAt = now; drawOverlay(); }
}

function stats() {
  const e = S.engine;
  const b = S.batches;
  const span = b.length > 1 ? b[b.length - 1][0] - b[0][0] : 0;
  const ticksInWindow = b.slice(1).reduce((s, [, n]) => s + n, 0);
  const ticksAll = b.reduce((s, [, n]) => s + n, 0), wallAll = b.reduce((s, [, , w]) => s + w, 0);
  const ts = e ? e.tickStats() : {};
  const isolated = !!self.crossOriginIsolated;
  return {
    model: S.model ? S.model.id : null,
    ticks: S.ticks,
    dropped: S.dropped,
    ticksPerSecond: span > 0 ? (1000 * ticksInWindow) / span : 0,
    fps: S.frameTimes.length > 1 ? (1000 * (S.frameTimes.length - 1)) / (S.frameTimes[S.frameTimes.length - 1] - S.frameTimes[0]) : 0,
    // C++ compute time per tick (steady_clock = performance.now: 5 us resolution when cross-origin
    // isolated, as `medspring view` serves the page; 100 us otherwise)
    medianTickUs: ts.median ?? NaN,
    p99TickUs: ts.p99 ?? NaN,
    meanTickUs: ts.mean ?? NaN,
    wallTickUs: ticksAll > 0 ? (1000 * wallAll) / ticksAll : NaN,  // JS wall time per tick over the last second
    crossOriginIsolated: isolated,
    renderMs: S.renderMs.length ? [...S.renderMs].sort((a, b) => a - b)[S.renderMs.length >> 1] : NaN,
    reaction: e ? e.reaction() : [0, 0, 0],
    grabbed: e ? e.grabbed() : false,
    mode: S.mode,
    tool: e ? e.toolState() : null,
    maxDisplacement: e ? e.maxDisplacement() : 0,
  };
}

function drawOverlay() {
  const st = stats();
  const f = st.reaction;
  const fm = Math.hypot(f[0], f[1], f[2]);
  const o = $('overlay');
  if (!o.querySelector('canvas')) {
    o.innerHTML = '<div id="ov-text"></div><canvas id="plot" width="250" height="60"></canvas>';
  }
  const tick = st.crossOriginIsolated ? `median <b>${st.medianTickUs.toFixed(1)} µs</b> · wall ${st.wallTickUs.toFixed(1)} µs`
    : `wall <b>${st.wallTickUs.toFixed(1)} µs</b>`;
  $('ov-text').innerHTML =
    `tick (1 ms) ${tick}<br>` +
    `physics <b>${st.ticksPerSecond.toFixed(0)} ticks/s</b> · ${st.fps.toFixed(0)} fps` +
    (st.dropped ? ` · ${st.dropped} ticks dropped` : '') + '<br>' +
    `reaction <b>${fm.toFixed(3)} N</b> (${f.map((v) => v.toFixed(3)).join(', ')})<br>` +
    `max |u| ${st.maxDisplacement.toFixed(3)} mm · t ${(S.engine.time() / 1000).toFixed(1)} s`;
  const c = $('plot'), g = c.getContext('2d');
  g.clearRect(0, 0, c.width, c.height);
  g.fillStyle = 'rgba(255,255,255,0.06)';
  g.fillRect(0, 0, c.width, c.height);
  const top = Math.max(0.05, ...S.forces.map(([, v]) => v)) * 1.1;
  const now = performance.now();
  g.strokeStyle = '#ffd24a';
  g.beginPath();
  S.forces.forEach(([t, v], i) => {
    const x = (1 - (now - t) / 5000) * (c.width - 1), y = c.height - 1 - (v / top) * (c.height - 2);
    if (i) g.lineTo(x, y); else g.moveTo(x, y);
  });
  g.stroke();
  g.fillStyle = '#9aa5b4';
  g.font = '10px monospace';
  g.fillText(`|F| (N), last 5 s, max ${top.toFixed(2)}`, 4, 10);
}

// ---------------------------------------------------------------- test and bench hooks
function canvasStats() {
  renderer.render(scene, camera);
  const gl = renderer.getContext();
  const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  const px = new Uint8Array(4 * w * h);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  const bg = [0x1d, 0x22, 0x29];
  let fg = 0;
  const colours = new Set();
  for (let i = 0; i < px.length; i += 4) {
    if (Math.abs(px[i] - bg[0]) + Math.abs(px[i + 1] - bg[1]) + Math.abs(px[i + 2] - bg[2]) > 12) ++fg;
    if (i % 64 === 0) colours.add((px[i] << 16) | (px[i + 1] << 8) | px[i + 2]);
  }
  return { width: w, height: h, foreground: fg / (w * h), colours: colours.size };
}

/// Client coordinates of surface node i as displayed now.
function project(i) {
  const P = S.engine.positions();
  const v = new THREE.Vector3(P[3 * i], P[3 * i + 1], P[3 * i + 2]).project(camera);
  const r = renderer.domElement.getBoundingClientRect();
  return { x: r.left + ((v.x + 1) / 2) * r.width, y: r.top + ((1 - v.y) / 2) * r.height, depth: v.z };
}

/// Benchmark: a trajectory replay (per-tick compute, as `medspring haptics`) and a pressed batch.
function bench({ model = 'kidney_phantom', csv, contact = 223, local = false, batch = 2000 } = {}) {
  const out = {};
  if (csv) {
    const e = new S.ms.Engine(model, true, local);
    e.benchTrajectory(csv, contact);  // warm-up
    e.reset();
    out.trajectory = e.benchTrajectory(csv, contact);
    out.trajectory.times = Array.from(out.trajectory.times);
    e.delete();
  }
  const e = new S.ms.Engine(model, true, local);
  e.grab(contact, K_VC0, B_VC, F_MAX);
  const t = e.tool();
  e.moveTool(t[0], t[1], t[2] - 3);
  e.ticks(200);
  const t0 = performance.now();
  e.ticks(batch);
  out.batch = { ticks: batch, meanUs: (1000 * (performance.now() - t0)) / batch, stats: e.tickStats() };
  e.delete();
  out.crossOriginIsolated = self.crossOriginIsolated;
  return out;
}

function setMode(m) {
  if (!['probe', 'grasp', 'pull'].includes(m)) throw new Error(`unknown mode '${m}' (probe, grasp or pull)`);
  if (S.drag) { S.drag = null; if (S.engine) S.engine.release(); }
  S.mode = m;
  $('mode').value = m;
}
function showToolValues() {
  if (!S.size) return;
  const sz = toolSizes();
  $('radius-val').textContent = `${sz.radius.toFixed(1)} mm`;
  $('depth-val').textContent = `${sz.depth.toFixed(1)} mm`;
  $('friction-val').textContent = Number($('friction').value).toFixed(2);
}

// ---------------------------------------------------------------- start
export async function start() {
  const api = {
    THREE,
    get module() { return S.ms; },
    get engine() { return S.engine; },
    get model() { return S.model; },
    get models() { return S.models; },
    get camera() { return camera; },
    get renderer() { return renderer; },
    get error() { return S.error; },
    get message() { return S.message; },
    get ready() { return !!S.engine && !S.loading; },
    set paused(v) { S.paused = !!v; },
    get mode() { return S.mode; },
    loadModel, pickAt, project, stats, canvasStats, bench, setMode, toolSizes,
  };
  window.medspring = api;
  makeScene();
  let createMedSpring;
  try {
    ({ default: createMedSpring } = await import('./dist/medspring.mjs'));
    S.ms = await createMedSpring();
  } catch (err) {
    showError(`Could not load the engine (dist/medspring.mjs — build it with web/build.sh): ${errorText(err)}`);
    renderer.render(scene, camera);
    return;
  }
  api.failed = undefined;

  const canvas = renderer.domElement;
  canvas.addEventListener('pointerdown', onPointerDown);
  canvas.addEventListener('pointermove', onPointerMove);
  canvas.addEventListener('pointerup', onPointerUp);
  canvas.addEventListener('pointercancel', onPointerUp);
  canvas.addEventListener('lostpointercapture', onPointerUp);
  $('model').addEventListener('change', (ev) => loadModel(ev.target.value));
  $('error').addEventListener('click', () => showError(''));  // dismiss
  $('local').addEventListener('change', (ev) => {
    try { S.engine.setLocal(ev.target.checked); } catch (err) { showError(errorText(err)); }
  });
  for (const id of ['k', 'eta', 'kr', 'beta']) $(id).addEventListener('input', onParamInput);
  $('nonlinear').addEventListener('change', onParamInput);
  $('defaults').addEventListener('click', () => {
    setSlidersTo({ ...S.defaults, nonlinear: $('nonlinear').checked });
    onParamInput();
  });
  $('kvc').addEventListener('input', () => { S.kvc = logSlider('kvc', K_VC0); showParamValues(sliderParams()); });
  $('reset').addEventListener('click', () => { S.drag = null; S.engine.reset(); });
  $('mode').addEventListener('change', (ev) => setMode(ev.target.value));
  for (const id of ['radius', 'depth', 'friction']) $(id).addEventListener('input', showToolValues);
  const m = new URLSearchParams(location.search).get('mode');
  if (m) setMode(m);

  await loadModelList();
  const wanted = new URLSearchParams(location.search).get('model');
  const first = S.models.find((m) => m.id === wanted) || S.models[0];
  await loadModel(first.id);
  setInterval(pump, 1);
  requestAnimationFrame(frame);
}
