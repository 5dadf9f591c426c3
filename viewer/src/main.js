// The chokeloops viewer: reads the data the C++ side (src/view.cpp) embedded in view.html and shows the
// surface, the loops, the table of loops and the persistence diagrams. Bundled with three.js into one IIFE.
// URL fragment "#render" hides the side panel and draws one frame synchronously (for headless screenshots).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

export const COLORS = {
  'handle generator': '#e41a1c',
  'handle choke': '#ff8c00',
  'tunnel generator': '#1f5fe0',
  'tunnel choke': '#12a339',
};
const HIGHLIGHT = '#ffd500';
const SURFACE = '#c9c4ba';
const HIDDEN = 0.55;  // opacity of the parts of loops behind the surface

const state = {
  ready: false, webgl: false, rendered: false, renderMode: false,
  loopCount: 0, selectedLoop: null, profileLoop: null, surfaceOpacity: 1,
  displayFaces: 0, sourceFaces: 0, decimated: false, surfaceKind: 'marching', hasInputMesh: false,
  sort: { key: 'persistence', dir: 'desc' }, errors: [],
};
window.chokeloopsView = state;
window.addEventListener('error', (e) => state.errors.push(String(e.message || e)));

const $ = (tag, attrs = {}, ...children) => {
  const el = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === 'class') el.className = v;
    else if (k === 'text') el.textContent = v;
    else if (k.startsWith('on')) el.addEventListener(k.slice(2), v);
    else el.setAttribute(k, v);
  }
  for (const c of children) if (c != null) el.append(c);
  return el;
};
const SVGNS = 'http://www.w3.org/2000/svg';
const svg = (tag, attrs = {}) => {
  const el = document.createElementNS(SVGNS, tag);
  for (const [k, v] of Object.entries(attrs)) el.setAttribute(k, v);
  return el;
};
const fmt = (x) => {
  if (typeof x !== 'number' || !isFinite(x)) return '–';
  if (x === 0) return '0';
  const a = Math.abs(x);
  if (a >= 1e4 || a < 1e-3) return x.toExponential(2);
  return String(Number(x.toPrecision(4)));
};
const category = (l) => `${l.side} ${l.kind}`;

function decodeBase64(text) {
  const s = text.replace(/[^A-Za-z0-9+/]/g, '');
  const table = new Uint8Array(128);
  const abc = 'ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/';
  for (let i = 0; i < 64; i++) table[abc.charCodeAt(i)] = i;
  const n = Math.floor(s.length * 3 / 4);
  const out = new Uint8Array(n);
  let o = 0, i = 0;
  for (; i + 4 <= s.length; i += 4) {
    const v = (table[s.charCodeAt(i)] << 18) | (table[s.charCodeAt(i + 1)] << 12) |
      (table[s.charCodeAt(i + 2)] << 6) | table[s.charCodeAt(i + 3)];
    out[o++] = v >> 16; out[o++] = (v >> 8) & 255; out[o++] = v & 255;
  }
  const rest = s.length - i;
  if (rest >= 2) {
    const v = (table[s.charCodeAt(i)] << 18) | (table[s.charCodeAt(i + 1)] << 12) |
      (rest === 3 ? table[s.charCodeAt(i + 2)] << 6 : 0);
    out[o++] = v >> 16;
    if (rest === 3) out[o++] = (v >> 8) & 255;
  }
  return out.buffer.slice(0, o);
}

// Eigen-decomposition of a symmetric 3x3 matrix (Jacobi); returns eigenvectors sorted by decreasing eigenvalue.
function eigenSym3(m) {
  const a = m.map((r) => r.slice());
  const v = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
  for (let sweep = 0; sweep < 50; sweep++) {
    let off = Math.abs(a[0][1]) + Math.abs(a[0][2]) + Math.abs(a[1][2]);
    if (off < 1e-15) break;
    for (const [p, q] of [[0, 1], [0, 2], [1, 2]]) {
      if (Math.abs(a[p][q]) < 1e-300) continue;
      const theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
      const t = Math.sign(theta || 1) / (Math.abs(theta) + Math.sqrt(theta * theta + 1));
      const c = 1 / Math.sqrt(t * t + 1), s = t * c;
      for (let k = 0; k < 3; k++) {
        const akp = a[k][p], akq = a[k][q];
        a[k][p] = c * akp - s * akq; a[k][q] = s * akp + c * akq;
      }
      for (let k = 0; k < 3; k++) {
        const apk = a[p][k], aqk = a[q][k];
        a[p][k] = c * apk - s * aqk; a[q][k] = s * apk + c * aqk;
      }
      for (let k = 0; k < 3; k++) {
        const vkp = v[k][p], vkq = v[k][q];
        v[k][p] = c * vkp - s * vkq; v[k][q] = s * vkp + c * vkq;
      }
    }
  }
  return [0, 1, 2].map((i) => ({ value: a[i][i], vector: new THREE.Vector3(v[0][i], v[1][i], v[2][i]) }))
    .sort((x, y) => y.value - x.value);
}

// Loops lie on the surface, so a triangulated surface hides parts of them: move their fragments toward the
// camera by `pull` (along the view ray: the screen position stays) so that whatever lies within that
// distance of the surface still shows as visible.
function pullTowardCamera(material, pull) {
  material.onBeforeCompile = (shader) => {
    shader.uniforms.loopPull = { value: pull };
    shader.vertexShader = 'uniform float loopPull;\n' + shader.vertexShader.replace('#include <project_vertex>',
      '#include <project_vertex>\nmvPosition.xyz += normalize(-mvPosition.xyz) * loopPull;\ngl_Position = projectionMatrix * mvPosition;');
  };
  material.customProgramCacheKey = () => 'chokeloops-pull';
  return material;
}

function readData() {
  const data = JSON.parse(document.getElementById('chokeloops-data').textContent);
  const bytes = (id) => { const el = document.getElementById(id); return el ? decodeBase64(el.textContent) : new ArrayBuffer(0); };
  const pos = new Float32Array(bytes('chokeloops-positions'));
  const idx = new Uint32Array(bytes('chokeloops-indices'));
  const inputPos = new Float32Array(bytes('chokeloops-input-positions'));
  const inputIdx = new Uint32Array(bytes('chokeloops-input-indices'));
  return { data, pos, idx, inputPos, inputIdx };
}

function main() {
  state.renderMode = /(^|[#&?])render\b/.test(location.hash + location.search);
  if (state.renderMode) document.body.classList.add('render');
  const read = readData();
  const data = read.data;
  // A mesh input's page also holds the input mesh and its loops (input_loops.json); view.html#input shows
  // those instead of the marching surface's.
  const input = data.input_view && Array.isArray(data.input_view.loops) && read.inputIdx.length >= 3 ? data.input_view : null;
  state.hasInputMesh = !!input;
  const showInput = !!input && /(^|[#&])input\b/.test(location.hash);
  state.surfaceKind = showInput ? 'input' : 'marching';
  const pos = showInput ? read.inputPos : read.pos;
  const idx = showInput ? read.inputIdx : read.idx;
  const mesh = (showInput ? input.mesh : data.mesh) || {};
  let report = data.report || {};
  if (showInput) {
    report = { ...report, loops: input.loops,
      surface: { ...(report.surface || {}), vertices: mesh.source_vertices, faces: mesh.source_faces } };
  }
  const loops = (report.loops || []).filter((l) => l && Array.isArray(l.points));
  loops.forEach((l, i) => {
    if (typeof l.id !== 'number' || !isFinite(l.id)) l.id = i;
    l.points = l.points.filter((p) => Array.isArray(p) && p.length >= 3 && Number.isFinite(p[0]) && Number.isFinite(p[1]) && Number.isFinite(p[2]));
  });
  if (new Set(loops.map((l) => l.id)).size !== loops.length) loops.forEach((l, i) => { l.id = i; });
  state.loopCount = loops.length;
  state.displayFaces = idx.length / 3;
  state.sourceFaces = mesh.source_faces ?? idx.length / 3;
  state.decimated = !!mesh.decimated;
  const byId = new Map(loops.map((l) => [l.id, l]));

  const viewer = buildScene(pos, idx, loops);
  const panel = document.getElementById('panel');
  const ui = buildPanel(panel, report, mesh, loops, viewer);
  buildLegend(document.getElementById('viewport'), loops, viewer, report);

  state.select = (id, opts = {}) => {
    const l = byId.get(id);
    state.selectedLoop = l ? l.id : null;
    viewer.highlight(l || null, opts.frame !== false);
    ui.highlight(state.selectedLoop);
  };
  state.setOpacity = (v) => viewer.setOpacity(v);
  state.screenPosition = (id, k = 0) => viewer.screenPosition(id, k);
  state.timeFrames = (n = 10) => (viewer.timeFrames ? viewer.timeFrames(n) : null);
  window.addEventListener('keydown', (e) => { if (e.key === 'Escape') state.select(null); });
  state.categories = Object.keys(COLORS).reduce((o, c) => (o[c] = loops.filter((l) => category(l) === c).length, o), {});
  state.ready = true;
  // view.html#loop=ID opens with that loop selected.
  const m = /(?:^#|[#&])loop=(-?\d+)/.exec(location.hash);
  if (m && byId.has(Number(m[1]))) state.select(Number(m[1]), { frame: !state.renderMode });
  if (state.renderMode) { viewer.resetView(); state.rendered = viewer.ok; }
}

function buildScene(pos, idx, loops) {
  const viewport = document.getElementById('viewport');
  const canvas = document.getElementById('canvas');
  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  } catch (e) {
    viewport.append($('div', { class: 'error legend', style: 'top:auto;bottom:10px', 'data-testid': 'webgl-error',
      text: 'WebGL is not available in this browser: the 3D view is off; the table and diagrams still work.' }));
    const noop = () => {};
    return { ok: false, highlight: noop, setOpacity: noop, renderNow: noop, setCategoryVisible: noop, resetView: noop, screenPosition: () => null };
  }
  state.webgl = true;
  renderer.setPixelRatio(state.renderMode ? 1 : Math.min(window.devicePixelRatio || 1, 2));
  renderer.setClearColor(new THREE.Color('#f4f5f7'), 1);
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(35, 1, 1e-3, 1e3);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8f99, 1.1));
  const headlight = new THREE.DirectionalLight(0xffffff, 1.6);
  headlight.position.set(0.3, 0.6, 1);
  camera.add(headlight);
  scene.add(camera);

  // Surface.
  const geom = new THREE.BufferGeometry();
  geom.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  geom.setIndex(new THREE.BufferAttribute(idx, 1));
  geom.computeVertexNormals();
  geom.computeBoundingBox();
  geom.computeBoundingSphere();
  const surfaceMat = new THREE.MeshPhongMaterial({ color: SURFACE, side: THREE.DoubleSide, shininess: 18, specular: 0x222222 });
  const surface = new THREE.Mesh(geom, surfaceMat);
  surface.renderOrder = 0;
  scene.add(surface);

  const box = geom.boundingBox ? geom.boundingBox.clone() : new THREE.Box3();
  for (const l of loops) for (const p of l.points) box.expandByPoint(new THREE.Vector3(p[0], p[1], p[2]));
  if (box.isEmpty()) box.set(new THREE.Vector3(-1, -1, -1), new THREE.Vector3(1, 1, 1));
  const sphere = box.getBoundingSphere(new THREE.Sphere());
  const diag = Math.max(sphere.radius * 2, 1e-9);
  const tubeR = diag * 0.0045;
  camera.near = diag * 1e-3; camera.far = diag * 50;

  // Loops: an occluded pass (see-through, faint) and a visible pass; plus a halo for the selected loop.
  const loopObjs = new Map();
  const ballGeom = new THREE.SphereGeometry(tubeR * 1.9, 16, 12);
  const haloMaterial = new THREE.MeshBasicMaterial({ color: HIGHLIGHT, side: THREE.BackSide, transparent: true, opacity: 0.9, depthTest: false, depthWrite: false });
  for (const l of loops) {
    let pts = l.points.map((p) => new THREE.Vector3(p[0], p[1], p[2]));
    if (pts.length > 2 && pts[0].distanceTo(pts[pts.length - 1]) < 1e-12) pts = pts.slice(0, -1);
    if (pts.length < 2) continue;
    const closed = pts.length >= 3;
    const curve = new THREE.CatmullRomCurve3(pts, closed, 'centripetal');
    const segs = Math.min(Math.max(pts.length * 2, 64), 4000);
    const tube = new THREE.TubeGeometry(curve, segs, tubeR, 8, closed);
    const color = new THREE.Color(COLORS[category(l)] || '#888888');
    const hidden = new THREE.Mesh(tube, new THREE.MeshBasicMaterial({ color, transparent: true, opacity: HIDDEN, depthTest: false, depthWrite: false }));
    hidden.renderOrder = 2;
    const visible = new THREE.Mesh(tube, pullTowardCamera(new THREE.MeshLambertMaterial({ color, emissive: color.clone().multiplyScalar(0.4), transparent: true, opacity: 1, depthWrite: true }), tubeR * 3));
    visible.renderOrder = 3;
    visible.userData.loopId = l.id;
    const group = new THREE.Group();
    group.add(hidden, visible);
    if (Array.isArray(l.choke_point) && l.choke_point.length === 3 && l.choke_point.every(Number.isFinite)) {
      const c = new THREE.Vector3(...l.choke_point);
      const ballHidden = new THREE.Mesh(ballGeom, new THREE.MeshBasicMaterial({ color: 0x222222, transparent: true, opacity: HIDDEN, depthTest: false, depthWrite: false }));
      ballHidden.renderOrder = 2; ballHidden.position.copy(c);
      const ball = new THREE.Mesh(ballGeom, pullTowardCamera(new THREE.MeshLambertMaterial({ color: 0x2a2a2a, transparent: true, opacity: 1 }), tubeR * 3));
      ball.renderOrder = 3; ball.position.copy(c); ball.userData.loopId = l.id;
      group.add(ballHidden, ball);
    }
    const lbox = new THREE.Box3().setFromPoints(pts);
    scene.add(group);
    // The halo of the selected loop is made when first needed.
    const makeHalo = () => {
      const halo = new THREE.Mesh(new THREE.TubeGeometry(curve, segs, tubeR * 2.1, 8, closed), haloMaterial);
      halo.renderOrder = 1;
      group.add(halo);
      return halo;
    };
    loopObjs.set(l.id, { group, halo: null, makeHalo, hidden, visible, loop: l, sphere: lbox.getBoundingSphere(new THREE.Sphere()) });
  }

  // Default view: look along the direction in which the loops spread least (so they are seen face-on),
  // tilted by 30 degrees for depth; loops weighted equally. Without loops, use the surface's spread.
  const cov = [[0, 0, 0], [0, 0, 0], [0, 0, 0]];
  const mean = new THREE.Vector3();
  let wsum = 0;
  const samples = [];
  if (loops.length) {
    for (const l of loops) for (const p of l.points) samples.push([p[0], p[1], p[2], 1 / l.points.length]);
  } else {
    const step = Math.max(1, Math.floor(pos.length / 3 / 20000));
    for (let i = 0; i < pos.length / 3; i += step) samples.push([pos[3 * i], pos[3 * i + 1], pos[3 * i + 2], 1]);
  }
  for (const s of samples) { mean.x += s[0] * s[3]; mean.y += s[1] * s[3]; mean.z += s[2] * s[3]; wsum += s[3]; }
  let viewDir = new THREE.Vector3(1, 0.8, 0.6).normalize();
  let up = new THREE.Vector3(0, 0, 1);
  if (wsum > 0 && samples.length >= 3) {
    mean.divideScalar(wsum);
    for (const s of samples) {
      const d = [s[0] - mean.x, s[1] - mean.y, s[2] - mean.z];
      for (let i = 0; i < 3; i++) for (let j = 0; j < 3; j++) cov[i][j] += s[3] * d[i] * d[j];
    }
    const eig = eigenSym3(cov);
    if (eig[0].value > 0) {
      const tilt = (30 * Math.PI) / 180;
      viewDir = eig[2].vector.clone().multiplyScalar(Math.cos(tilt)).addScaledVector(eig[1].vector, Math.sin(tilt)).normalize();
      if (viewDir.dot(new THREE.Vector3(1, 1, 1)) < 0) viewDir.negate();
      // "Up" is the input's +y (the usual convention of mesh files), or +z when the view is along y.
      const worldUp = Math.abs(viewDir.y) < 0.9 ? new THREE.Vector3(0, 1, 0) : new THREE.Vector3(0, 0, 1);
      up = worldUp.addScaledVector(viewDir, -worldUp.dot(viewDir)).normalize();
    }
  }
  camera.up.copy(up);
  const controls = state.renderMode ? null : new OrbitControls(camera, canvas);

  function fitDistance(radius) {
    const vfov = (camera.fov * Math.PI) / 180;
    const hfov = 2 * Math.atan(Math.tan(vfov / 2) * camera.aspect);
    return (radius * 1.08) / Math.sin(Math.min(vfov, hfov) / 2);
  }
  function resize() {
    const w = Math.max(1, viewport.clientWidth || window.innerWidth), h = Math.max(1, viewport.clientHeight || window.innerHeight);
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
  }
  // Points whose projection must fit in the default view: a sample of the surface and all loop points.
  const fitPoints = [];
  {
    const nv = pos.length / 3, step = Math.max(1, Math.floor(nv / 30000));
    for (let i = 0; i < nv; i += step) fitPoints.push(new THREE.Vector3(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]));
    for (const l of loops) for (const p of l.points) fitPoints.push(new THREE.Vector3(p[0], p[1], p[2]));
    if (!fitPoints.length) fitPoints.push(sphere.center.clone());
  }
  function resetView() {
    resize();
    // Centre the projected extent and move back until every point is inside the frustum (with a margin).
    const right = new THREE.Vector3().crossVectors(up, viewDir).normalize();
    const upv = new THREE.Vector3().crossVectors(viewDir, right).normalize();
    let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
    for (const p of fitPoints) {
      const d = p.clone().sub(sphere.center);
      const x = d.dot(right), y = d.dot(upv);
      x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y);
    }
    const center = sphere.center.clone().addScaledVector(right, (x0 + x1) / 2).addScaledVector(upv, (y0 + y1) / 2);
    const vh = Math.max(1, viewport.clientHeight || window.innerHeight), vw = Math.max(1, viewport.clientWidth || window.innerWidth);
    const place = (band) => {
      // band > 0: fit below a band of that many pixels at the top, shifting the image down by half of it.
      if (band > 0) camera.setViewOffset(vw, vh, 0, -band / 2, vw, vh);
      else camera.clearViewOffset();
      const t = Math.tan((camera.fov * Math.PI) / 360) * 0.94;
      const tv = t * ((vh - band) / vh), th = t * camera.aspect;
      let dist = 0;
      for (const p of fitPoints) {
        const d = p.clone().sub(center);
        const z = d.dot(viewDir);
        dist = Math.max(dist, Math.abs(d.dot(right)) / th + z, Math.abs(d.dot(upv)) / tv + z);
      }
      dist = Math.max(dist, sphere.radius * 0.05);
      camera.position.copy(center).addScaledVector(viewDir, dist);
      camera.lookAt(center);
      camera.updateMatrixWorld();
    };
    place(0);
    // In a picture, the legend sits in the top-left corner: if the shape would run under it, fit below it.
    const legend = state.renderMode && document.querySelector('[data-testid=legend]');
    if (legend) {
      const r = legend.getBoundingClientRect(), v = viewport.getBoundingClientRect();
      const lx = r.right - v.left + 6, ly = r.bottom - v.top + 6;
      const under = fitPoints.some((p) => {
        const q = p.clone().project(camera);
        return ((q.x + 1) / 2) * vw < lx && ((1 - q.y) / 2) * vh < ly;
      });
      if (under) place(Math.min(vh * 0.3, ly));
    }
    if (controls) { controls.target.copy(center); controls.update(); }
    render();
  }
  let pending = false;
  function render() {
    if (state.renderMode) { renderer.render(scene, camera); return; }
    if (pending) return;
    pending = true;
    requestAnimationFrame(() => { pending = false; renderer.render(scene, camera); });
  }
  let anim = null;
  function flyTo(target, dist) {
    const dir = camera.position.clone().sub(controls ? controls.target : sphere.center).normalize();
    const fromT = (controls ? controls.target : sphere.center).clone(), toT = target.clone();
    const fromP = camera.position.clone(), toP = target.clone().addScaledVector(dir, dist);
    const t0 = performance.now();
    if (anim) cancelAnimationFrame(anim);
    const step = () => {
      const t = Math.min(1, (performance.now() - t0) / 450), e = t * t * (3 - 2 * t);
      camera.position.lerpVectors(fromP, toP, e);
      if (controls) { controls.target.lerpVectors(fromT, toT, e); controls.update(); }
      renderer.render(scene, camera);
      anim = t < 1 ? requestAnimationFrame(step) : null;
    };
    step();
  }
  if (controls) {
    controls.addEventListener('change', render);
    window.addEventListener('resize', () => { resize(); render(); });
    // Click on a loop (or its choke point) to select it.
    const ray = new THREE.Raycaster();
    let down = null;
    canvas.addEventListener('pointerdown', (e) => { down = [e.clientX, e.clientY]; });
    canvas.addEventListener('pointerup', (e) => {
      if (!down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 4) return;
      const r = canvas.getBoundingClientRect();
      ray.setFromCamera(new THREE.Vector2(((e.clientX - r.left) / r.width) * 2 - 1, -((e.clientY - r.top) / r.height) * 2 + 1), camera);
      const targets = [];
      for (const o of loopObjs.values()) if (o.group.visible) o.group.traverse((m) => { if (m.userData.loopId !== undefined) targets.push(m); });
      const hit = ray.intersectObjects(targets, false)[0];
      if (hit) state.select(hit.object.userData.loopId, { frame: false });
    });
  }
  resetView();

  return {
    ok: true,
    // Where on the page point k of a loop is drawn (for tests and tools): {x, y} in CSS pixels.
    screenPosition(id, k) {
      const o = loopObjs.get(id);
      if (!o) return null;
      const p = o.loop.points[((k % o.loop.points.length) + o.loop.points.length) % o.loop.points.length];
      const v = new THREE.Vector3(p[0], p[1], p[2]).project(camera);
      const r = canvas.getBoundingClientRect();
      return { x: r.left + ((v.x + 1) / 2) * r.width, y: r.top + ((1 - v.y) / 2) * r.height };
    },
    renderNow() { resize(); renderer.render(scene, camera); },
    // Milliseconds per frame over n synchronous renders, the camera orbiting (for tests).
    timeFrames(n) {
      const gl = renderer.getContext(), px = new Uint8Array(4);
      const t0 = performance.now();
      for (let i = 0; i < n; i++) {
        camera.position.applyAxisAngle(camera.up, 0.05);
        camera.lookAt(controls ? controls.target : sphere.center);
        renderer.render(scene, camera);
        gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);  // wait for the frame
      }
      return (performance.now() - t0) / n;
    },
    resetView,
    highlight(loop, frame) {
      for (const o of loopObjs.values()) {
        const on = loop != null && o.loop.id === loop.id;
        if (on && !o.halo) o.halo = o.makeHalo();
        if (o.halo) o.halo.visible = on;
        o.hidden.material.opacity = on ? 1 : HIDDEN;  // the selected loop shows whole, through the surface
      }
      const o = loop && loopObjs.get(loop.id);
      if (o && frame && controls) {
        o.group.visible = true;
        flyTo(o.sphere.center, Math.max(fitDistance(o.sphere.radius) * 4, diag * 0.6));
      } else render();
    },
    setOpacity(v) {
      const a = Math.min(1, Math.max(0.02, Number(v)));
      state.surfaceOpacity = a;
      surfaceMat.opacity = a;
      surfaceMat.transparent = a < 1;
      surfaceMat.depthWrite = a >= 1;
      surfaceMat.needsUpdate = true;
      render();
    },
    setCategoryVisible(cat, on) {
      for (const o of loopObjs.values()) if (category(o.loop) === cat) o.group.visible = on;
      render();
    },
  };
}

function buildLegend(viewport, loops, viewer, report) {
  const legend = $('div', { class: 'legend', 'data-testid': 'legend' });
  if (state.renderMode) {
    const g = report.surface && report.surface.genus;
    legend.append($('div', { class: 'caption', text: `${report.input ?? 'chokeloops'}${g !== undefined ? ` · genus ${g}` : ''} · ${loops.length} loop${loops.length === 1 ? '' : 's'}` }));
  }
  for (const [cat, color] of Object.entries(COLORS)) {
    const mine = loops.filter((l) => category(l) === cat);
    const n = mine.length, drawn = mine.filter((l) => l.points.length >= 2).length;
    const box = $('input', { type: 'checkbox', 'data-testid': `legend-toggle-${cat.replace(' ', '-')}` });
    box.checked = true;
    box.addEventListener('change', () => viewer.setCategoryVisible(cat, box.checked));
    legend.append($('label', { 'data-category': cat }, box,
      $('span', { class: `swatch ${cat.split(' ')[1]}`, style: `background:${color}` }),
      $('span', { text: `${cat} (${drawn === n ? n : `${drawn} of ${n} drawn`})` })));
  }
  legend.append($('div', { class: 'muted', style: 'margin-top:3px', text: '● choke point' }));
  viewport.append(legend);
}

function buildPanel(panel, report, mesh, loops, viewer) {
  const surf = report.surface || {};
  const params = report.parameters || {};
  panel.append($('h1', { text: `chokeloops: ${report.input ?? 'analysis'}` }));
  panel.append($('div', { class: 'muted', 'data-testid': 'surface-kind', 'data-kind': state.surfaceKind,
    text: state.surfaceKind === 'input' ? 'loops on the input mesh (input_loops.json)' : 'loops on the marching surface of the grid (loops.json)' }));
  const count = $('span', { 'data-testid': 'loop-count', 'data-count': String(loops.length), text: String(loops.length) });
  const missing = loops.filter((l) => l.points.length < 2).length;
  panel.append($('div', {}, count, ` loop${loops.length === 1 ? '' : 's'}${missing ? ` (${missing} without a polyline)` : ''} · genus ${surf.genus ?? '?'} · ${surf.components ?? '?'} component(s)`));
  for (const w of Array.isArray(report.warnings) ? report.warnings : []) panel.append($('div', { class: 'note', 'data-testid': 'warning', text: String(w) }));
  const stats = $('dl', { class: 'stats' });
  const add = (k, v) => { if (v !== undefined && v !== null && v !== '') stats.append($('dt', { text: k }), $('dd', { text: String(v) })); };
  add('voxel size', report.voxel_size !== undefined ? `${fmt(report.voxel_size)} (${report.units ?? 'input'} units)` : undefined);
  add('grid', report.grid && report.grid.dims ? report.grid.dims.join(' × ') : undefined);
  add('surface', `${surf.vertices ?? mesh.source_vertices} vertices, ${surf.faces ?? mesh.source_faces} faces`);
  add('d_max', params.d_max !== undefined ? `${params.d_max}` + (params.d_max_abs_handle !== undefined
    ? ` = ${fmt(params.d_max_abs_handle)} (handle), ${fmt(params.d_max_abs_tunnel)} (tunnel)`
    : params.d_max_abs !== undefined ? ` = ${fmt(params.d_max_abs)}` : '') : undefined);
  add('δ_min', params.min_persistence !== undefined ? `${params.min_persistence}` +
    (params.min_persistence_abs_handle !== undefined ? ` = ${fmt(params.min_persistence_abs_handle)} (handle), ${fmt(params.min_persistence_abs_tunnel)} (tunnel)` : '') : undefined);
  if (report.timings_ms && report.timings_ms.total !== undefined) add('time', `${fmt(report.timings_ms.total / 1000)} s`);
  panel.append(stats);
  if (mesh.decimated) {
    panel.append($('div', { class: 'note', 'data-testid': 'decimation-note',
      text: `Surface decimated for display: ${mesh.display_faces} of ${mesh.source_faces} faces shown (vertex clustering, cell ${fmt(mesh.cell_size)}). The loops and numbers come from the full surface.` }));
  }

  panel.append($('h2', { text: 'View' }));
  const slider = $('input', { type: 'range', min: '0.05', max: '1', step: '0.05', value: '1', 'data-testid': 'opacity-slider', 'aria-label': 'surface opacity' });
  slider.addEventListener('input', () => viewer.setOpacity(slider.value));
  panel.append($('div', { class: 'controls' },
    $('label', {}, 'surface opacity ', slider),
    $('button', { type: 'button', 'data-testid': 'reset-view', onclick: () => { state.select(null); viewer.resetView(); } }, 'reset view'),
    $('button', { type: 'button', 'data-testid': 'save-png', title: 'save the 3D view as a PNG', onclick: () => {
      viewer.renderNow();
      const a = $('a', { href: document.getElementById('canvas').toDataURL('image/png'), download: `${String(report.input ?? 'chokeloops').replace(/[^\w.-]+/g, '_')}-loops.png` });
      document.body.append(a); a.click(); a.remove();
    } }, 'save PNG'),
    state.hasInputMesh ? $('button', { type: 'button', 'data-testid': 'surface-toggle', onclick: () => {
      const rest = location.hash.replace(/^#/, '').split('&').filter((p) => p && p !== 'input');
      if (state.surfaceKind !== 'input') rest.unshift('input');
      location.hash = rest.join('&');
      location.reload();
    } }, state.surfaceKind === 'input' ? 'show the marching surface' : 'show the input mesh') : null));
  panel.append($('div', { class: 'muted', style: 'margin-top:4px', text: 'Drag to rotate, scroll to zoom, right-drag to pan; click a loop, a row or a diagram point to select it.' }));

  // Table of loops.
  panel.append($('h2', { text: 'Loops' }));
  const cols = [
    ['id', '#', (l) => l.id], ['side', 'side', (l) => l.side], ['kind', 'kind', (l) => l.kind],
    ['depth', 'depth', (l) => l.depth], ['persistence', 'persistence', (l) => l.persistence], ['length', 'length', (l) => l.length],
  ];
  const table = $('table', { 'data-testid': 'loop-table' });
  const headRow = $('tr');
  const ths = {};
  for (const [key, label] of cols) {
    const th = $('th', { 'data-key': key, 'data-testid': `sort-${key}`, scope: 'col', text: label,
      title: key === 'depth' ? 'inscribed radius at the choke (handles); distance outside (tunnels)' : `sort by ${label}` });
    th.addEventListener('click', () => {
      state.sort = { key, dir: state.sort.key === key && state.sort.dir === 'asc' ? 'desc' : 'asc' };
      fillRows();
    });
    ths[key] = th;
    headRow.append(th);
  }
  const tbody = $('tbody');
  table.append($('thead', {}, headRow), tbody);
  const rows = new Map();
  for (const l of loops) {
    const cat = category(l);
    const tr = $('tr', { 'data-testid': 'loop-row', 'data-loop-id': String(l.id), 'aria-selected': 'false' },
      $('td', { text: String(l.id) }),
      $('td', {}, $('span', { class: `swatch ${l.kind}`, style: `background:${COLORS[cat] || '#888'};margin-right:4px` }), l.side),
      $('td', { text: l.kind }), $('td', { text: fmt(l.depth) }), $('td', { text: fmt(l.persistence) }),
      l.points.length >= 2 ? $('td', { text: fmt(l.length) }) : $('td', { class: 'muted', text: 'no loop' }));
    if (l.points.length < 2) {
      tr.classList.add('missing');
      tr.title = typeof l.note === 'string' && l.note ? l.note : 'no loop was found for this choke';
    }
    tr.tabIndex = 0;
    tr.addEventListener('click', () => state.select(l.id));
    tr.addEventListener('keydown', (e) => { if (e.key === 'Enter' || e.key === ' ') { e.preventDefault(); state.select(l.id); } });
    rows.set(l.id, tr);
  }
  function fillRows() {
    const col = cols.find((c) => c[0] === state.sort.key) || cols[0];
    const sgn = state.sort.dir === 'asc' ? 1 : -1;
    const sorted = loops.slice().sort((a, b) => {
      const x = col[2](a), y = col[2](b);
      const c = typeof x === 'number' && typeof y === 'number' ? x - y : String(x).localeCompare(String(y));
      return sgn * c || a.id - b.id;
    });
    for (const [key, th] of Object.entries(ths)) th.setAttribute('aria-sort', key === state.sort.key ? (state.sort.dir === 'asc' ? 'ascending' : 'descending') : 'none');
    tbody.replaceChildren(...sorted.map((l) => rows.get(l.id)));
    state.rowOrder = sorted.map((l) => l.id);
  }
  fillRows();
  panel.append(loops.length ? $('div', { class: 'table-wrap' }, table) : $('div', { class: 'muted', 'data-testid': 'no-loops', text: 'No loops passed the thresholds.' }));

  // Radius profiles of molecular channels (loops.json's channel.profile), drawn for the selected tunnel.
  const profiled = loops.filter((l) => l.channel);
  let profileBox = null;
  if (profiled.length) {
    panel.append($('h2', { text: 'Channel profile' }));
    profileBox = $('div', { class: 'diagram', 'data-testid': 'profile-panel' });
    panel.append(profileBox);
  }
  const showProfile = (id) => {
    if (!profileBox) return;
    const l = loops.find((x) => x.id === id);
    state.profileLoop = null;
    if (!l || !l.channel) {
      profileBox.replaceChildren($('div', { class: 'muted', text: 'Select a tunnel to see its radius profile.' }));
      return;
    }
    const c = l.channel, p = c.profile || {};
    const s = Array.isArray(p.s) ? p.s : [], r = Array.isArray(p.radius) ? p.radius : [];
    const pts = s.map((x, k) => [x, r[k]]).filter((q) => Number.isFinite(q[0]) && Number.isFinite(q[1]));
    const head = $('div', { text: `tunnel ${l.id}: bottleneck ${fmt(c.bottleneck_radius)} Å` +
      (Number.isFinite(c.length) && c.length > 0 ? `, path ${fmt(c.length)} Å` : '') });
    const lining = Array.isArray(c.bottleneck_lining) ? c.bottleneck_lining.slice(0, 6)
      .map((a) => `${a.chain}:${a.resname}${a.resseq}`).filter((v, k, all) => all.indexOf(v) === k) : [];
    const rest = [head];
    if (lining.length) rest.push($('div', { class: 'muted', text: `lined by ${lining.join(', ')}` }));
    if (pts.length < 2) {
      rest.push($('div', { class: 'note', 'data-testid': 'profile-note', text: c.note || 'no profile was traced for this tunnel' }));
      profileBox.replaceChildren(...rest);
      return;
    }
    state.profileLoop = l.id;
    profileBox.replaceChildren(...rest, drawProfile(l.id, pts, c.bottleneck_radius));
  };
  showProfile(null);

  // Persistence diagrams.
  panel.append($('h2', { text: 'Persistence diagrams' }));
  const diag = report.diagram || {};
  const points = new Map();
  const wrap = $('div', { class: 'diagrams' });
  for (const side of ['handle', 'tunnel']) {
    const cand = Array.isArray(diag[side]) ? diag[side] : [];
    const mine = loops.filter((l) => l.side === side);
    const dmax = Number.isFinite(params[`d_max_abs_${side}`]) ? params[`d_max_abs_${side}`] : params.d_max_abs;
    const pmin = params[`min_persistence_abs_${side}`];
    wrap.append(drawDiagram(side, cand, mine, dmax, pmin, points));
  }
  panel.append(wrap);

  return {
    highlight(id) {
      for (const [lid, tr] of rows) {
        const on = lid === id;
        tr.classList.toggle('selected', on);
        tr.setAttribute('aria-selected', on ? 'true' : 'false');
        if (on && !state.renderMode) tr.scrollIntoView({ block: 'nearest' });
      }
      for (const [lid, els] of points) for (const el of els) el.classList.toggle('selected', lid === id);
      showProfile(id);
    },
  };
}

// Round tick values 0, s, 2s, ... below max, with s = 1, 2 or 5 times a power of ten (about 5 ticks).
function niceTicks(max) {
  const raw = max / 5, p = Math.pow(10, Math.floor(Math.log10(raw)));
  const s = [1, 2, 5, 10].map((m) => m * p).find((v) => v >= raw) || raw;
  const out = [];
  for (let k = 0; k * s <= max * (1 + 1e-9) && out.length < 12; k++) out.push(Number((k * s).toPrecision(6)));
  return out;
}

// Radius against signed distance along the channel (0 at the bottleneck), as HOLE plots it.
function drawProfile(id, pts, bottleneck) {
  const W = 400, H = 220, ml = 46, mr = 12, mt = 14, mb = 34;
  const s0 = Math.min(...pts.map((q) => q[0])), s1 = Math.max(...pts.map((q) => q[0]));
  const rMax = (Math.max(...pts.map((q) => q[1])) || 1) * 1.08;
  const span = s1 - s0 || 1;
  const X = (x) => ml + ((x - s0) / span) * (W - ml - mr), Y = (y) => H - mb - (y / rMax) * (H - mt - mb);
  const root = svg('svg', { viewBox: `0 0 ${W} ${H}`, 'data-testid': 'profile-plot', 'data-loop-id': String(id),
    'data-points': String(pts.length), role: 'img', 'aria-label': `radius profile of tunnel ${id}` });
  root.append(svg('line', { x1: ml, y1: Y(0), x2: W - mr, y2: Y(0), stroke: '#444' }));
  root.append(svg('line', { x1: ml, y1: Y(0), x2: ml, y2: Y(rMax), stroke: '#444' }));
  const step = niceTicks(span)[1] || span;
  for (let xv = Math.ceil(s0 / step) * step; xv <= s1 + 1e-9; xv += step) {
    const tx = svg('text', { x: X(xv), y: Y(0) + 13, 'font-size': 9.5, 'text-anchor': 'middle', fill: '#555' }); tx.textContent = fmt(Number(xv.toPrecision(6)));
    root.append(svg('line', { x1: X(xv), y1: Y(0), x2: X(xv), y2: Y(0) + 3, stroke: '#444' }), tx);
  }
  for (const yv of niceTicks(rMax)) {
    const ty = svg('text', { x: ml - 4, y: Y(yv) + 3, 'font-size': 9.5, 'text-anchor': 'end', fill: '#555' }); ty.textContent = fmt(yv);
    root.append(svg('line', { x1: ml - 3, y1: Y(yv), x2: ml, y2: Y(yv), stroke: '#444' }), ty);
  }
  const xl = svg('text', { x: (ml + W - mr) / 2, y: H - 6, 'font-size': 11, 'text-anchor': 'middle' });
  xl.textContent = 'distance along the channel from the bottleneck (Å)';
  const yl = svg('text', { x: 12, y: (Y(0) + Y(rMax)) / 2, 'font-size': 11, 'text-anchor': 'middle', transform: `rotate(-90 12 ${(Y(0) + Y(rMax)) / 2})` });
  yl.textContent = 'radius (Å)';
  root.append(xl, yl);
  if (Number.isFinite(bottleneck)) {
    root.append(svg('line', { x1: ml, y1: Y(bottleneck), x2: W - mr, y2: Y(bottleneck), stroke: '#b03030', 'stroke-dasharray': '5 3' }));
  }
  root.append(svg('polyline', { points: pts.map((q) => `${X(q[0]).toFixed(1)},${Y(q[1]).toFixed(1)}`).join(' '),
    fill: 'none', stroke: COLORS['tunnel generator'], 'stroke-width': 2, 'data-testid': 'profile-line' }));
  if (s0 <= 0 && s1 >= 0 && Number.isFinite(bottleneck))
    root.append(svg('circle', { cx: X(0), cy: Y(bottleneck), r: 3.5, fill: '#b03030', 'data-testid': 'profile-bottleneck' }));
  return root;
}

function drawDiagram(side, cand, loops, dmax, pmin, points) {
  const W = 400, H = 250, ml = 52, mr = 12, mt = 22, mb = 36;
  const xs = cand.map((p) => p[0]).concat(loops.map((l) => l.depth)).filter(Number.isFinite);
  const ys = cand.map((p) => p[1]).concat(loops.map((l) => l.persistence)).filter(Number.isFinite);
  if (Number.isFinite(dmax)) xs.push(dmax);
  if (Number.isFinite(pmin)) ys.push(pmin);
  const xMax = (Math.max(0, ...xs) || 1) * 1.08, yMax = (Math.max(0, ...ys) || 1) * 1.1;
  const X = (x) => ml + (x / xMax) * (W - ml - mr), Y = (y) => H - mb - (y / yMax) * (H - mt - mb);
  const root = svg('svg', { viewBox: `0 0 ${W} ${H}`, 'data-testid': `diagram-${side}`, role: 'img', 'aria-label': `${side} persistence diagram` });
  const title = svg('text', { x: ml, y: 14, 'font-size': 12, 'font-weight': 600 });
  title.textContent = `${side}s: ${loops.length} loop(s), ${cand.length} candidate(s)`;
  root.append(title);
  if (Number.isFinite(dmax) && Number.isFinite(pmin)) {
    root.append(svg('rect', { x: X(0), y: Y(yMax), width: X(Math.min(dmax, xMax)) - X(0), height: Y(pmin) - Y(yMax), fill: '#e3f4e1', 'data-testid': `accept-region-${side}` }));
  }
  // Axes and ticks.
  root.append(svg('line', { x1: X(0), y1: Y(0), x2: X(xMax), y2: Y(0), stroke: '#444' }));
  root.append(svg('line', { x1: X(0), y1: Y(0), x2: X(0), y2: Y(yMax), stroke: '#444' }));
  for (const xv of niceTicks(xMax)) {
    const tx = svg('text', { x: X(xv), y: Y(0) + 13, 'font-size': 9.5, 'text-anchor': 'middle', fill: '#555' }); tx.textContent = fmt(xv);
    root.append(svg('line', { x1: X(xv), y1: Y(0), x2: X(xv), y2: Y(0) + 3, stroke: '#444' }), tx);
  }
  for (const yv of niceTicks(yMax)) {
    const ty = svg('text', { x: X(0) - 4, y: Y(yv) + 3, 'font-size': 9.5, 'text-anchor': 'end', fill: '#555' }); ty.textContent = fmt(yv);
    root.append(svg('line', { x1: X(0) - 3, y1: Y(yv), x2: X(0), y2: Y(yv), stroke: '#444' }), ty);
  }
  const xl = svg('text', { x: (X(0) + X(xMax)) / 2, y: H - 6, 'font-size': 11, 'text-anchor': 'middle' });
  xl.textContent = side === 'handle' ? 'depth (inscribed radius at the choke)' : 'distance (outside, at the choke)';
  const yl = svg('text', { x: 12, y: (Y(0) + Y(yMax)) / 2, 'font-size': 11, 'text-anchor': 'middle', transform: `rotate(-90 12 ${(Y(0) + Y(yMax)) / 2})` });
  yl.textContent = 'persistence';
  root.append(xl, yl);
  // Thresholds.
  if (Number.isFinite(dmax)) {
    root.append(svg('line', { x1: X(dmax), y1: Y(0), x2: X(dmax), y2: Y(yMax), stroke: '#b03030', 'stroke-dasharray': '5 3', 'data-testid': `threshold-dmax-${side}` }));
    const t = svg('text', { x: X(dmax) - 3, y: Y(yMax) + 10, 'font-size': 10, 'text-anchor': 'end', fill: '#b03030' }); t.textContent = `d_max = ${fmt(dmax)}`;
    root.append(t);
  }
  if (Number.isFinite(pmin)) {
    root.append(svg('line', { x1: X(0), y1: Y(pmin), x2: X(xMax), y2: Y(pmin), stroke: '#3050b0', 'stroke-dasharray': '5 3', 'data-testid': `threshold-pmin-${side}` }));
    const t = svg('text', { x: X(xMax) - 3, y: Y(pmin) - 4, 'font-size': 10, 'text-anchor': 'end', fill: '#3050b0' }); t.textContent = `δ_min = ${fmt(pmin)}`;
    root.append(t);
  }
  for (const p of cand) {
    if (!Number.isFinite(p[0]) || !Number.isFinite(p[1])) continue;
    const c = svg('circle', { cx: X(p[0]), cy: Y(p[1]), r: 2.6, fill: '#9aa1ad', 'data-testid': 'diagram-candidate' });
    const t = svg('title'); t.textContent = `${side === 'handle' ? 'depth' : 'distance'} ${fmt(p[0])}, persistence ${fmt(p[1])}`;
    c.append(t);
    root.append(c);
  }
  // Chokes (diamonds) under generators (circles), so both show when they share a point.
  for (const l of loops.slice().sort((a, b) => (a.kind === 'choke' ? -1 : 1) - (b.kind === 'choke' ? -1 : 1))) {
    if (!Number.isFinite(l.depth) || !Number.isFinite(l.persistence)) continue;
    const cx = X(l.depth), cy = Y(l.persistence), color = COLORS[category(l)] || '#888';
    const el = l.kind === 'choke'
      ? svg('path', { d: `M${cx},${cy - 7.5}L${cx + 7.5},${cy}L${cx},${cy + 7.5}L${cx - 7.5},${cy}Z`, fill: color, stroke: '#fff', 'stroke-width': 1 })
      : svg('circle', { cx, cy, r: 5, fill: color, stroke: '#fff', 'stroke-width': 1 });
    el.setAttribute('class', 'pt');
    el.setAttribute('data-testid', 'diagram-point');
    el.setAttribute('data-loop-id', String(l.id));
    const t = svg('title');
    t.textContent = `loop ${l.id}: ${category(l)}, ${side === 'handle' ? 'depth' : 'distance'} ${fmt(l.depth)}, persistence ${fmt(l.persistence)}`;
    el.append(t);
    el.addEventListener('click', () => state.select(l.id));
    if (!points.has(l.id)) points.set(l.id, []);
    points.get(l.id).push(el);
    root.append(el);
  }
  return $('div', { class: 'diagram' }, root);
}

try {
  main();
} catch (e) {
  state.errors.push(String(e && e.stack || e));
  console.error('chokeloops viewer:', e);
  const panel = document.getElementById('panel');
  if (panel) panel.prepend($('div', { class: 'error', 'data-testid': 'viewer-error', text: `The viewer failed: ${e && e.message || e}` }));
}
