// The viewer's page: three.js scene (map points, keyframe frustums, edges, camera, trajectories), the
// current image with person boxes and keypoints, status bar and run controls. Offline: three.js and
// OrbitControls come from our own server.
#include <string>

#include "crowdslam/viewer/viewer_server.h"

namespace crowdslam::viewer {

const std::string& viewer_page_html() {
  static const std::string page = R"PAGE(<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>crowdslam viewer</title>
<style>
 body { margin: 0; font: 13px sans-serif; background: #111; color: #ddd; overflow: hidden; }
 #scene { position: absolute; left: 0; top: 32px; right: 0; bottom: 28px; }
 #bar { position: absolute; left: 0; right: 0; top: 0; height: 32px; background: #222; display: flex; gap: 6px; align-items: center; padding: 0 8px; }
 #status { position: absolute; left: 0; right: 0; bottom: 0; height: 28px; line-height: 28px; background: #222; padding: 0 8px; white-space: nowrap; overflow: hidden; contain: strict; }
 #imagebox { position: absolute; right: 8px; top: 40px; width: 36%; max-width: 640px; border: 1px solid #444; line-height: 0; }
 #image { width: 100%; height: auto; display: block; }
 button, label { color: #ddd; background: #333; border: 1px solid #555; padding: 3px 8px; border-radius: 3px; }
 #legend { margin-left: auto; color: #999; }
</style></head>
<body>
<div id="bar">
 <button id="pause">Pause</button><button id="step">Step</button><button id="resume">Resume</button>
 <label><input type="checkbox" id="follow" checked> follow camera</label>
 <label><input type="checkbox" id="edges"> covisibility / loop edges</label>
 <label><input type="checkbox" id="showimage" checked> image</label>
 <span id="legend">points: grey, new: red &middot; keyframes: blue &middot; camera: green &middot; trajectory: yellow &middot; ground truth: orange</span>
</div>
<div id="scene"></div>
<div id="imagebox"><canvas id="image" width="640" height="480"></canvas></div>
<div id="status">connecting...</div>
<script>
 document.body.dataset.errors = "0";
 window.addEventListener('error', function () { document.body.dataset.errors = String(Number(document.body.dataset.errors) + 1); });
</script>
<script src="/three.min.js"></script>
<script src="/OrbitControls.js"></script>
<script>
(function () {
 'use strict';
 const body = document.body;
 const params = new URLSearchParams(location.search);
 const noRender = Boolean(params.get('norender'));  // diagnostics: no WebGL drawing
 // WebGL drawn by the CPU (SwiftShader, llvmpipe: no GPU, or a headless browser) takes the cores SLAM
 // runs on: then no antialiasing (4x the pixels to shade) and half the page updates.
 // The renderer starts without antialiasing and is made again with it when the GPU draws.
 function isSoftware(renderer) {
  const gl = renderer.getContext(), info = gl.getExtension('WEBGL_debug_renderer_info');
  return /swiftshader|llvmpipe|softpipe|software/i.test(info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : '');
 }
 let renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
 const softwareGl = isSoftware(renderer);
 if (!softwareGl) { renderer.dispose(); renderer.forceContextLoss(); renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true }); }
 // The event handlers only keep the newest state; apply() shows it at most 4 times a second (2 with
 // software WebGL): every page update costs layout, painting and compositing.
 // ?update_ms=N chooses another interval (100-5000 ms), e.g. 1000 for a browser on a busy SLAM machine.
 const APPLY_INTERVAL_MS = params.get('update_ms') ? Math.min(5000, Math.max(100, Number(params.get('update_ms')) || 500))
  : (softwareGl ? 500 : 250);
 let updates = 0, renders = 0;
 body.dataset.updates = '0'; body.dataset.frame = '-1'; body.dataset.points = '0'; body.dataset.webgl = 'yes';
 body.dataset.softwareGl = String(softwareGl);

 // Scene: the SLAM frame is x right, y down, z forward; the root flips it so that up is up.
 const container = document.getElementById('scene');
 renderer.setClearColor(0x111111);
 container.appendChild(renderer.domElement);
 const scene = new THREE.Scene();
 const camera = new THREE.PerspectiveCamera(60, 1, 0.01, 1000);
 camera.position.set(0, 3, 4);
 const controls = new THREE.OrbitControls(camera, renderer.domElement);
 const root = new THREE.Group();
 root.rotation.x = Math.PI;
 scene.add(root);
 scene.add(new THREE.AxesHelper(0.3));

 // Drawing: only when something changed, never in a loop. Mouse moves draw on the next animation frame;
 // updates draw at once (a page whose animation frames are suspended, as in a headless screenshot, still
 // shows the newest state).
 function render() {
  if (noRender) return;
  renderer.render(scene, camera);
  renders += 1; body.dataset.renders = String(renders);
 }
 let renderQueued = false;
 function renderNextFrame() {
  if (renderQueued) return;
  renderQueued = true;
  requestAnimationFrame(function () { renderQueued = false; render(); });
 }
 controls.addEventListener('change', renderNextFrame);

 function resize() {
  const w = container.clientWidth || 800, h = container.clientHeight || 600;
  renderer.setSize(w, h); camera.aspect = w / h; camera.updateProjectionMatrix();
  renderNextFrame();
 }
 window.addEventListener('resize', function () { resize(); if (source && imageShown() && shownImageWidth() !== imageWidth) connect(); });
 resize();

 // Map points.
 const pointGeometry = new THREE.BufferGeometry();
 const pointCloud = new THREE.Points(pointGeometry, new THREE.PointsMaterial({ size: 3, sizeAttenuation: false, vertexColors: true }));
 root.add(pointCloud);
 let knownIds = new Set();
 // Keyframes, edges, camera, trajectories.
 const keyframeLines = new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0x4488ff }));
 const edgeLines = new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0x557799, transparent: true, opacity: 0.5 }));
 const loopLines = new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0xff33ff }));
 edgeLines.visible = loopLines.visible = false;
 root.add(keyframeLines, edgeLines, loopLines);
 const trajectory = [];
 const trajectoryLine = new THREE.Line(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0xffdd33 }));
 const groundTruthLine = new THREE.Line(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0xff8800 }));
 root.add(trajectoryLine, groundTruthLine);
 const cameraLines = new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: 0x33ff66 }));
 root.add(cameraLines);
 let scale = 0.1;  // frustum size: 2 % of the map's extent, between 2 and 15 cm (set with the map)

 function frustum(pose, size, out) {
  const m = new THREE.Matrix4().compose(new THREE.Vector3(pose[0], pose[1], pose[2]),
                                        new THREE.Quaternion(pose[3], pose[4], pose[5], pose[6]), new THREE.Vector3(1, 1, 1));
  const w = size, h = 0.75 * size, d = size;
  const c = [[0, 0, 0], [-w, -h, d], [w, -h, d], [w, h, d], [-w, h, d]].map(p => new THREE.Vector3(p[0], p[1], p[2]).applyMatrix4(m));
  const pairs = [[0, 1], [0, 2], [0, 3], [0, 4], [1, 2], [2, 3], [3, 4], [4, 1]];
  for (const [a, b] of pairs) out.push(c[a].x, c[a].y, c[a].z, c[b].x, c[b].y, c[b].z);
 }
 function setPositions(geometry, values) {
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(values, 3));
  geometry.computeBoundingSphere();
 }

 let keyframePoses = new Map();
 let mapInfo = { points: 0, keyframes: 0, loops: 0 };
 function showMap(m) {
  const n = m.point_ids.length, pos = new Float32Array(3 * n), col = new Float32Array(3 * n), ids = new Set();
  let min = [Infinity, Infinity, Infinity], max = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < n; ++i) {
   for (let k = 0; k < 3; ++k) {
    const v = m.points_mm[3 * i + k] / 1000; pos[3 * i + k] = v;
    if (v < min[k]) min[k] = v; if (v > max[k]) max[k] = v;
   }
   const id = m.point_ids[i]; ids.add(id);
   const fresh = knownIds.size > 0 && !knownIds.has(id);
   const g = Math.min(1, 0.45 + 0.05 * m.observations[i]);
   col[3 * i] = fresh ? 1 : g; col[3 * i + 1] = fresh ? 0.2 : g; col[3 * i + 2] = fresh ? 0.2 : g;
  }
  knownIds = ids;
  pointGeometry.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  pointGeometry.setAttribute('color', new THREE.BufferAttribute(col, 3));
  pointGeometry.computeBoundingSphere();
  if (n > 0) scale = Math.min(0.15, Math.max(0.02, 0.02 * Math.max(max[0] - min[0], max[1] - min[1], max[2] - min[2])));
  keyframePoses = new Map();
  const lines = [];
  for (const kf of m.keyframes) { keyframePoses.set(kf.id, kf.pose); frustum(kf.pose, scale, lines); }
  setPositions(keyframeLines.geometry, lines);
  const edge = (list) => { const out = []; for (const [a, b] of list) { const p = keyframePoses.get(a), q = keyframePoses.get(b); if (p && q) out.push(p[0], p[1], p[2], q[0], q[1], q[2]); } return out; };
  setPositions(edgeLines.geometry, edge(m.covisibility));
  setPositions(loopLines.geometry, edge(m.loop_edges));
  mapInfo = { points: n, keyframes: m.keyframes.length, loops: m.loops_closed };
  body.dataset.points = String(n);
 }
 function showFrame(f) {
  body.dataset.frame = String(f.index);
  setPositions(trajectoryLine.geometry, trajectory);
  if (!f.pose) return;
  const lines = []; frustum(f.pose, 1.5 * scale, lines); setPositions(cameraLines.geometry, lines);
  if (document.getElementById('follow').checked) {
   root.updateMatrixWorld();
   const p = new THREE.Vector3(f.pose[0], f.pose[1], f.pose[2]).applyMatrix4(root.matrixWorld);
   const shift = p.clone().sub(controls.target); controls.target.copy(p); camera.position.add(shift);
  }
 }
 const statusBar = document.getElementById('status');
 let note = '';  // 'map reset', 'run completed', 'disconnected'
 function showStatus(f) {
  const text = f ? ['frame ' + f.index, f.state + (f.method ? ' (' + f.method + ')' : ''), f.fps.toFixed(1) + ' frames/s',
   'keyframes ' + mapInfo.keyframes, 'points ' + mapInfo.points, 'loops ' + mapInfo.loops,
   'people ' + (100 * f.people_area).toFixed(1) + ' %', 'budget ' + f.feature_budget, f.paused ? 'PAUSED' : ''] : [note ? '' : 'waiting for the run'];
  const line = text.concat(note ? [note] : []).filter(Boolean).join('  |  ');
  if (statusBar.textContent !== line) statusBar.textContent = line;  // no layout when nothing changed
 }
 // The image: only the newest, only while shown, one decode at a time.
 const imageBox = document.getElementById('imagebox'), canvas = document.getElementById('image'), ctx = canvas.getContext('2d');
 let decoding = false, imagesDrawn = 0;
 function imageShown() { return document.getElementById('showimage').checked; }
 function showImage(m) {
  const img = new Image();
  decoding = true;
  img.onerror = function () { decoding = false; };
  img.onload = function () {
   decoding = false;
   if (canvas.width !== m.width || canvas.height !== m.height) { canvas.width = m.width; canvas.height = m.height; }
   ctx.drawImage(img, 0, 0); imagesDrawn += 1;
   ctx.lineWidth = 2; ctx.strokeStyle = '#3388ff';
   for (const b of m.boxes) ctx.strokeRect(b[0], b[1], b[2], b[3]);
   const dots = (flat, colour) => { ctx.fillStyle = colour; for (let i = 0; i + 1 < flat.length; i += 2) ctx.fillRect(flat[i] - 1.5, flat[i + 1] - 1.5, 3, 3); };
   dots(m.kept, '#33ff66'); dots(m.removed, '#ff3333');
  };
  img.src = 'data:image/jpeg;base64,' + m.jpeg;
 }

 // The newest state not shown yet (raw JSON text: a superseded image or map is never parsed).
 const pending = { frame: null, map: null, image: null, groundTruth: null, trajectory: null };
 let lastFrame = null, applyTimer = 0, lastApply = -Infinity;
 function scheduleApply() {
  if (applyTimer) return;
  applyTimer = setTimeout(apply, Math.max(0, lastApply + APPLY_INTERVAL_MS - performance.now()));
 }
 function apply() {
  applyTimer = 0; lastApply = performance.now();
  let changed = false;
  if (pending.map) { showMap(JSON.parse(pending.map)); pending.map = null; changed = true; }
  if (pending.groundTruth) { setPositions(groundTruthLine.geometry, JSON.parse(pending.groundTruth).positions); pending.groundTruth = null; changed = true; }
  if (pending.trajectory) { setPositions(trajectoryLine.geometry, pending.trajectory); pending.trajectory = null; changed = true; }
  if (pending.frame) { lastFrame = pending.frame; pending.frame = null; showFrame(lastFrame); changed = true; }
  if (pending.image && imageShown() && !decoding) { showImage(JSON.parse(pending.image)); pending.image = null; }
  showStatus(lastFrame);
  if (changed) render();
  maybeClick();
  if (pending.image && imageShown()) scheduleApply();  // decoding the previous one: try again later
 }

 // Events.
 function count() { updates += 1; body.dataset.updates = String(updates); maybeClick(); scheduleApply(); }
 // The server sends images only to pages that show them (it encodes none when no page does), no wider
 // than shown (in steps of 160 device pixels).
 let source = null, imageWidth = 0, session = null;
 function startAfresh() {
  trajectory.length = 0; knownIds = new Set(); mapInfo = { points: 0, keyframes: 0, loops: 0 }; keyframePoses = new Map();
  for (const key of Object.keys(pending)) pending[key] = null;
  lastFrame = null; note = ''; delete body.dataset.finished; body.dataset.frame = '-1'; body.dataset.points = '0';
  for (const g of [pointGeometry, keyframeLines.geometry, edgeLines.geometry, loopLines.geometry, trajectoryLine.geometry,
                   groundTruthLine.geometry, cameraLines.geometry]) setPositions(g, []);
  pointGeometry.deleteAttribute('color');
  scheduleApply();
 }
 function shownImageWidth() { return 160 * Math.max(1, Math.ceil(imageBox.clientWidth * (window.devicePixelRatio || 1) / 160)); }
 function connect() {
  if (source) source.close();
  imageWidth = shownImageWidth();
  // In batches at the page's own update rate: the browser wakes twice or four times a second, not 15.
  source = new EventSource((imageShown() ? '/events?image_width=' + imageWidth : '/events?image=0') + '&batch_ms=' + APPLY_INTERVAL_MS);
  source.addEventListener('frame', e => {
   const f = JSON.parse(e.data);  // small; every pose goes into the trajectory
   if (f.pose) trajectory.push(f.pose[0], f.pose[1], f.pose[2]);
   pending.frame = f; count();
  });
  source.addEventListener('map', e => { pending.map = e.data; count(); });
  source.addEventListener('image', e => { pending.image = e.data; count(); });
  source.addEventListener('ground_truth', e => { pending.groundTruth = e.data; count(); });
  source.addEventListener('trajectory', e => {
   trajectory.length = 0; trajectory.push(...JSON.parse(e.data).positions); pending.trajectory = trajectory; count();
  });
  source.addEventListener('reset', e => { trajectory.length = 0; knownIds = new Set(); note = 'map reset'; count(); });
  source.addEventListener('finish', e => { body.dataset.finished = 'yes'; note = 'run ' + JSON.parse(e.data).end_state; count(); });
  source.onerror = function () { if (!body.dataset.finished) note = 'disconnected'; scheduleApply(); };  // EventSource reconnects by itself
  source.onopen = function () { if (note === 'disconnected') { note = ''; scheduleApply(); } };
  // Each server says its session first: a page left open across runs reconnects to the next run's server
  // and starts afresh (no reload: three.js and the WebGL context are kept).
  source.addEventListener('session', e => {
   const id = JSON.parse(e.data).id;
   if (session !== null && id !== session) startAfresh();
   session = id; body.dataset.session = id;
  });
 }
 connect();

 // Controls.
 function control(action) { return fetch('/control/' + action, { method: 'POST' }).then(r => r.json()).then(s => { body.dataset.paused = String(s.paused); }).catch(() => {}); }
 document.getElementById('pause').onclick = () => control('pause');
 document.getElementById('resume').onclick = () => control('resume');
 document.getElementById('step').onclick = () => control('step');
 document.getElementById('edges').onchange = e => { edgeLines.visible = loopLines.visible = e.target.checked; renderNextFrame(); };
 document.getElementById('follow').onchange = () => scheduleApply();
 document.getElementById('showimage').onchange = e => { imageBox.style.display = e.target.checked ? '' : 'none'; connect(); };
 // Tests: ?click=pause&after=N[&points=P] presses a button after N updates (and once P map points are shown).
 let clicked = false;
 function maybeClick() {
  const what = params.get('click');
  if (!what || clicked || updates < Number(params.get('after') || 10)) return;
  if (Number(body.dataset.points) < Number(params.get('points') || 0)) return;
  clicked = true; document.getElementById(what).click();
 }

 // Status back to the server once a second (GET /state shows it: tests and scripts read it there).
 setInterval(function () {
  fetch('/client', { method: 'POST', body: JSON.stringify({ updates: updates, errors: Number(body.dataset.errors),
   session: session,
   webgl: body.dataset.webgl, software_gl: softwareGl, renders: renders, images: imagesDrawn, frame: Number(body.dataset.frame), points: Number(body.dataset.points),
   paused: body.dataset.paused === 'true' }) }).catch(() => {});
 }, 1000);
 render();
})();
</script>
</body></html>
)PAGE";
  return page;
}

}  // namespace crowdslam::viewer
