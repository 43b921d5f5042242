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
 #status { position: absolute; left: 0; right: 0; bottom: 0; height: 28px; line-height: 28px; background: #222; padding: 0 8px; white-space: nowrap; overflow: hidden; }
 #imagebox { position: absolute; right: 8px; top: 40px; width: 36%; max-width: 640px; background: #000; border: 1px solid #444; line-height: 0; }
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
 let updates = 0, renders = 0, dirty = true;
 body.dataset.updates = '0'; body.dataset.frame = '-1'; body.dataset.points = '0'; body.dataset.webgl = 'no';

 // Scene: the SLAM frame is x right, y down, z forward; the root flips it so that up is up.
 const container = document.getElementById('scene');
 const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
 body.dataset.webgl = 'yes';
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

 function resize() {
  const w = container.clientWidth || 800, h = container.clientHeight || 600;
  renderer.setSize(w, h); camera.aspect = w / h; camera.updateProjectionMatrix();
 }
 window.addEventListener('resize', resize); resize();

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
 let scale = 0.1;  // frustum size: a tenth of the map's extent, at most 10 cm... updated with the map

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
 function onMap(m) {
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
 let mapInfo = { points: 0, keyframes: 0, loops: 0 };
 let lastFrame = null;
 function onFrame(f) {
  lastFrame = f;
  body.dataset.frame = String(f.index);
  if (f.pose) {
   trajectory.push(f.pose[0], f.pose[1], f.pose[2]);
   setPositions(trajectoryLine.geometry, trajectory);
   const lines = []; frustum(f.pose, 1.5 * scale, lines); setPositions(cameraLines.geometry, lines);
   if (document.getElementById('follow').checked) {
    const p = new THREE.Vector3(f.pose[0], f.pose[1], f.pose[2]).applyMatrix4(root.matrixWorld);
    const shift = p.clone().sub(controls.target); controls.target.copy(p); camera.position.add(shift);
   }
  }
  showStatus();
 }
 function showStatus(extra) {
  const f = lastFrame;
  const text = f ? ['frame ' + f.index, f.state + (f.method ? ' (' + f.method + ')' : ''), f.fps.toFixed(1) + ' frames/s',
   'keyframes ' + mapInfo.keyframes, 'points ' + mapInfo.points, 'loops ' + mapInfo.loops,
   'people ' + (100 * f.people_area).toFixed(1) + ' %', 'budget ' + f.feature_budget, f.paused ? 'PAUSED' : ''] : ['waiting for the run'];
  document.getElementById('status').textContent = text.concat(extra ? [extra] : []).filter(Boolean).join('  |  ');
 }
 const canvas = document.getElementById('image'), ctx = canvas.getContext('2d');
 function onImage(m) {
  const img = new Image();
  img.onload = function () {
   canvas.width = m.width; canvas.height = m.height; ctx.drawImage(img, 0, 0);
   ctx.lineWidth = 2; ctx.strokeStyle = '#3388ff';
   for (const b of m.boxes) ctx.strokeRect(b[0], b[1], b[2], b[3]);
   const dots = (flat, colour) => { ctx.fillStyle = colour; for (let i = 0; i + 1 < flat.length; i += 2) ctx.fillRect(flat[i] - 1.5, flat[i + 1] - 1.5, 3, 3); };
   dots(m.kept, '#33ff66'); dots(m.removed, '#ff3333');
  };
  img.src = 'data:image/jpeg;base64,' + m.jpeg;
 }
 function onTrajectory(m, line) { setPositions(line.geometry, m.positions); }

 // Events.
 function count() {
  updates += 1; body.dataset.updates = String(updates); dirty = true; maybeClick();
  setTimeout(renderSoon, 0);  // after the handler has applied the update
 }
 // Rendering is driven by animation frames, and also (throttled) by updates: a page whose animation
 // frames are suspended (hidden tab, headless screenshot) still shows the newest state.
 let lastRender = 0;
 function renderSoon() {
  const now = performance.now();
  if (now - lastRender < 200 || params.get('norender')) return;
  lastRender = now; dirty = false; renderer.render(scene, camera); renders += 1; body.dataset.renders = String(renders);
 }
 function connect() {
  const source = new EventSource('/events');
  source.addEventListener('frame', e => { count(); onFrame(JSON.parse(e.data)); });
  source.addEventListener('map', e => { count(); onMap(JSON.parse(e.data)); });
  source.addEventListener('image', e => { count(); onImage(JSON.parse(e.data)); });
  source.addEventListener('ground_truth', e => { count(); onTrajectory(JSON.parse(e.data), groundTruthLine); });
  source.addEventListener('trajectory', e => {
   count(); const m = JSON.parse(e.data); trajectory.length = 0; trajectory.push(...m.positions); onTrajectory(m, trajectoryLine);
  });
  source.addEventListener('reset', e => { count(); trajectory.length = 0; knownIds = new Set(); showStatus('map reset'); });
  source.addEventListener('finish', e => { count(); body.dataset.finished = 'yes'; showStatus('run ' + JSON.parse(e.data).end_state); });
  source.onerror = function () { showStatus('disconnected'); };
 }
 connect();

 // Controls.
 function control(action) { return fetch('/control/' + action, { method: 'POST' }).then(r => r.json()).then(s => { body.dataset.paused = String(s.paused); }).catch(() => {}); }
 document.getElementById('pause').onclick = () => control('pause');
 document.getElementById('resume').onclick = () => control('resume');
 document.getElementById('step').onclick = () => control('step');
 document.getElementById('edges').onchange = e => { edgeLines.visible = loopLines.visible = e.target.checked; };
 document.getElementById('showimage').onchange = e => { document.getElementById('imagebox').style.display = e.target.checked ? '' : 'none'; };
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
   webgl: body.dataset.webgl, renders: renders, frame: Number(body.dataset.frame), points: Number(body.dataset.points),
   paused: body.dataset.paused === 'true' }) }).catch(() => {});
 }, 1000);
 // Render only when something changed (software WebGL must not starve the event handlers).
 controls.addEventListener('change', () => { dirty = true; });
 function animate() {
  requestAnimationFrame(animate);
  if (!dirty || performance.now() - lastRender < 200) return;  // at most 5 renders a second
  dirty = false;
  if (params.get('norender')) return;
  lastRender = performance.now();
  renderer.render(scene, camera);
  renders += 1; body.dataset.renders = String(renders);
 }
 animate();
})();
</script>
</body></html>
)PAGE";
  return page;
}

}  // namespace crowdslam::viewer
