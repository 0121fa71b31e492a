// The three.js view (docs/web.md): the scene, the current model's objects (surface coloured by
// |displacement|, centerline, atoms, spokes), the tool (probe sphere, grasper jaws, coupling spring,
// force arrow), and the canvas hooks of the tests.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { $, S } from './state.js';

export let renderer, scene, camera, controls, mesh, restMesh, centerline, atoms, spokes, arrow, spring, toolDot, probeMesh, jaws;

export function makeScene() {
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
export function buildModelObjects() {
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
export function refreshGeometry() {
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

// ---------------------------------------------------------------- test hooks
export function canvasStats() {
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
export function project(i) {
  const P = S.engine.positions();
  const v = new THREE.Vector3(P[3 * i], P[3 * i + 1], P[3 * i + 2]).project(camera);
  const r = renderer.domElement.getBoundingClientRect();
  return { x: r.left + ((v.x + 1) / 2) * r.width, y: r.top + ((1 - v.y) / 2) * r.height, depth: v.z };
}
