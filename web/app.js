// phri dashboard: the page of `phri run --dashboard`. It draws the arm from the server-sent
// stream (/api/stream, ~60 frames a second), plots the last 10 s, and sends every operator action
// as one small JSON POST (/api/event, /api/gain, /api/push, ...); the server checks each one and
// the run loop takes it through the same events-and-targets path as the gamepad.
import * as THREE from 'three';
import { OrbitControls } from '/vendor/OrbitControls.js';
import uPlot from 'uplot';

const token = new URLSearchParams(location.search).get('token') || '';
const WINDOW_S = 10;          // plots show the last 10 s of robot time
const PLOT_PERIOD_MS = 12;    // plots redrawn with every frame, up to ~80 Hz (frames come at ~60 Hz)
const PUSH_N_PER_M = 300;     // push force per metre of drag from where the link was grabbed
const PUSH_RENEW_MS = 150;    // a held push is re-sent (the server ends a push 0.5 s after its last)

// A held push is renewed from a worker: its timer and its requests do not wait for the page's main
// thread, which a slow client (software WebGL, a loaded CPU) keeps busy for hundreds of ms at a time.
// The page hands it the latest request on every change and tells it when the push starts and ends.
const pushRenewer = new Worker(URL.createObjectURL(new Blob([`
  let timer = null, request = null;
  // Each renewal's send and reply times (the worker's clock) go back to the page: a gap in the push
  // is then either a renewal that came late (a starved machine; the server's hold ran out, as it must)
  // or a defect.
  const send = () => {
    if (!request) return;
    const sent = performance.now();
    fetch(request.url, request.init).then(() => postMessage([sent, performance.now()]),
                                          () => postMessage([sent, null]));
  };
  onmessage = ({ data }) => {
    if (data.request) request = data.request;
    if (data.start && timer === null) timer = setInterval(send, data.period);
    if (data.stop) { clearInterval(timer); timer = null; request = null; }
  };`], { type: 'text/javascript' })));

const $ = (id) => document.getElementById(id);
// Hooks for the browser test and for curious users (window.phri in the console).
const phri = (window.phri = { frames: 0, plotUpdates: 0, last: null, model: null, pushes: 0, replies: [], renewals: [] });
pushRenewer.onmessage = ({ data }) => {  // [sent ms, replied ms or null], the last 2000
  phri.renewals.push(data);
  if (phri.renewals.length > 2000) phri.renewals.shift();
};

async function post(action, body = {}) {
  const res = await fetch('/api/' + action, {
    method: 'POST',
    headers: { 'Content-Type': 'application/json', 'X-Phri-Token': token },
    body: JSON.stringify(body),
  });
  const reply = await res.json().catch(() => ({ ok: false, error: 'HTTP ' + res.status }));
  phri.replies.push({ action, status: res.status, reply });
  if (phri.replies.length > 50) phri.replies.shift();
  $('message').textContent = res.ok ? '' : `${action}: ${reply.error}`;
  return reply;
}

// ------------------------------------------------------------------ buttons and sliders
const EVENT_GROUPS = {
  'events-compliance': ['stiff_compliance', 'null_space_compliance', 'full_body_compliance', 'dual_compliance',
                        'stiffness_up', 'stiffness_down'],
  'events-loop': ['position_loop', 'kinova_torque_loop', 'kinova_torque_high_velocity_loop', 'custom_loop', 'toggle_loop'],
  'events-scenario': ['static_scenario', 'dynamic_scenario', 'toggle_scenario', 'stop_scenario', 'stop'],
};
const MODE_OF_EVENT = { stiff_compliance: 'stiff', null_space_compliance: 'null_space', full_body_compliance: 'full_body',
                        dual_compliance: 'dual' };
const LOOP_OF_EVENT = { position_loop: 'position', kinova_torque_loop: 'kinova_torque',
                        kinova_torque_high_velocity_loop: 'kinova_torque_high_velocity', custom_loop: 'custom' };

function buildButtons(model) {
  for (const [group, names] of Object.entries(EVENT_GROUPS)) {
    for (const name of names.filter((n) => model.events.includes(n))) {
      const b = document.createElement('button');
      b.id = 'event-' + name;
      b.textContent = name.replace(/_(compliance|loop)$/, '').replaceAll('_', ' ');
      if (name === 'stop') b.className = 'stop';
      b.onclick = () => post('event', { event: name });
      $(group).appendChild(b);
    }
  }
  $('run').onclick = () => post('run');
  $('pause').onclick = () => post('pause');
  $('step').onclick = () => post('step', { cycles: 1 });
  $('step10').onclick = () => post('step', { cycles: 10 });
  $('log').href = '/api/log?token=' + encodeURIComponent(token);
}

function buildSliders(model) {
  for (const g of model.gains) {
    const row = document.createElement('div');
    row.className = 'gain';
    const label = document.createElement('label');
    label.textContent = g.name.replaceAll('_', ' ');
    const input = document.createElement('input');
    Object.assign(input, { type: 'range', id: 'gain-' + g.name, min: g.min, max: g.max, step: (g.max - g.min) / 200 });
    const out = document.createElement('output');
    out.id = 'gain-value-' + g.name;
    let pending = null;
    // While the slider moves, at most one request every 100 ms; the last value always goes.
    input.oninput = () => {
      out.textContent = Number(input.value).toFixed(2);
      input.dataset.touched = String(Date.now());
      if (pending) return;
      pending = setTimeout(() => { pending = null; post('gain', { gain: g.name, value: Number(input.value) }); }, 100);
    };
    row.append(label, input, out);
    if (g.mode_value) {
      const auto = document.createElement('button');
      auto.textContent = 'mode';
      auto.title = 'give this gain back to the compliance mode';
      auto.onclick = () => post('gain', { gain: g.name, value: -1 });
      row.append(auto);
    } else {
      row.append(document.createElement('span'));
    }
    $('gains').appendChild(row);
  }
}

// Sliders follow the applied gains, except one the user moved in the last second.
function showGains(gains) {
  for (const [name, value] of Object.entries(gains)) {
    const input = $('gain-' + name), out = $('gain-value-' + name);
    if (!input) continue;
    out.textContent = value < 0 ? 'mode' : value.toFixed(2);
    if (Date.now() - Number(input.dataset.touched || 0) > 1000 && value >= 0) input.value = value;
  }
}

// ------------------------------------------------------------------ 3-D view
const view = { bodies: [], base: null, capsules: [], joints: [] };
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf7f9fb);
const camera = new THREE.PerspectiveCamera(45, 1, 0.01, 20);
camera.up.set(0, 0, 1);
camera.position.set(1.6, -1.3, 1.0);
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
$('scene').appendChild(renderer.domElement);
const controls = new OrbitControls(camera, renderer.domElement);
controls.target.set(0.3, 0, 0.45);
controls.update();
scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.5);
sun.position.set(2, -2, 3);
scene.add(sun);
const grid = new THREE.GridHelper(2, 20, 0x99aabb, 0xd0d8e0);
grid.rotation.x = Math.PI / 2;
scene.add(grid);

function frameAxes(size, opacity) {
  const axes = new THREE.AxesHelper(size);
  axes.material.transparent = opacity < 1;
  axes.material.opacity = opacity;
  axes.material.depthTest = false;
  axes.renderOrder = 2;
  scene.add(axes);
  return axes;
}
const eeAxes = frameAxes(0.12, 1.0);
const targetAxes = frameAxes(0.18, 0.45);
const pushArrow = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 0.1, 0xff6d00, 0.04, 0.025);
const wrenchArrow = new THREE.ArrowHelper(new THREE.Vector3(1, 0, 0), new THREE.Vector3(), 0.1, 0x8e24aa, 0.03, 0.02);
pushArrow.visible = wrenchArrow.visible = false;
for (const arrow of [pushArrow, wrenchArrow]) {  // drawn over the capsules they start inside
  arrow.traverse((o) => { if (o.material) o.material.depthTest = false; });
  arrow.renderOrder = 4;
}
scene.add(pushArrow, wrenchArrow);
const pairLine = new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]),
                                new THREE.LineBasicMaterial({ color: 0xd50000, depthTest: false }));
pairLine.renderOrder = 3;
scene.add(pairLine);

function buildArm(model) {
  view.base = new THREE.Group();
  scene.add(view.base);
  setPlacement(view.base, model.base);
  for (let b = 0; b < model.dof; ++b) {
    const g = new THREE.Group();
    scene.add(g);
    view.bodies.push(g);
    // The joint that moves this body, at its origin, coloured by its limit margin.
    const joint = new THREE.Mesh(new THREE.SphereGeometry(0.052, 20, 12), new THREE.MeshStandardMaterial({ color: 0x43a047 }));
    g.add(joint);
    view.joints.push(joint);
  }
  model.capsules.forEach((c, index) => {
    const p0 = new THREE.Vector3(...c.p0), p1 = new THREE.Vector3(...c.p1);
    const axis = p1.clone().sub(p0);
    const mesh = new THREE.Mesh(new THREE.CapsuleGeometry(c.radius, Math.max(axis.length(), 1e-4), 6, 20),
                                new THREE.MeshStandardMaterial({ color: 0x90a4ae, transparent: true, opacity: 0.8 }));
    mesh.position.copy(p0.clone().add(p1).multiplyScalar(0.5));
    if (axis.length() > 1e-9) mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), axis.normalize());
    mesh.userData = { capsule: index, body: c.body, link: c.link };
    (c.body >= 0 ? view.bodies[c.body] : view.base).add(mesh);
    view.capsules.push(mesh);
  });
}

function setPlacement(object, p) {
  object.position.set(p[0], p[1], p[2]);
  object.quaternion.set(p[4], p[5], p[6], p[3]);  // three.js: x, y, z, w
}

function setPose(object, pose) {
  object.position.set(...pose.p);
  object.quaternion.set(pose.q[1], pose.q[2], pose.q[3], pose.q[0]);
}

function setArrow(arrow, origin, vector, metresPerUnit) {
  const v = new THREE.Vector3(...vector);
  const length = v.length() * metresPerUnit;
  arrow.visible = length > 0.01;
  if (!arrow.visible) return;
  arrow.position.set(...origin);
  arrow.setDirection(v.normalize());
  arrow.setLength(length, Math.min(0.05, 0.3 * length), Math.min(0.03, 0.2 * length));
}

function showArm(f) {
  f.bodies.forEach((p, b) => setPlacement(view.bodies[b], p));
  f.margin.forEach((m, i) => view.joints[i].material.color.setHSL(0.33 * m, 0.8, 0.45));  // green -> red at a limit
  setPose(eeAxes, f.ee);
  setPose(targetAxes, f.target);
  if (f.push) setArrow(pushArrow, f.push.point, f.push.force, 0.006); else pushArrow.visible = false;
  setArrow(wrenchArrow, f.ee.p, f.wrench.slice(0, 3), 0.01);
  const names = f.collision ? new Set([f.collision.first, f.collision.second]) : new Set();
  for (const m of view.capsules) m.material.color.set(names.has(m.userData.link) ? 0xef9a9a : 0x90a4ae);
  pairLine.visible = !!f.collision;
  if (f.collision) {
    pairLine.geometry.setFromPoints([new THREE.Vector3(...f.collision.a), new THREE.Vector3(...f.collision.b)]);
    $('collision-readout').textContent =
      `closest pair: ${f.collision.first} – ${f.collision.second}: ${f.collision.distance_mm.toFixed(1)} mm`;
  }
}

function resize() {
  const el = $('scene');
  renderer.setSize(el.clientWidth, el.clientHeight);
  camera.aspect = el.clientWidth / el.clientHeight;
  camera.updateProjectionMatrix();
  renderer.render(scene, camera);
}
window.addEventListener('resize', resize);

// Where a point of a capsule (its middle by default) is on the page, for the browser test.
phri.screenOfCapsule = (index) => {
  const mesh = view.capsules[index];
  const p = mesh.getWorldPosition(new THREE.Vector3()).project(camera);
  const r = renderer.domElement.getBoundingClientRect();
  return { x: r.left + (p.x + 1) / 2 * r.width, y: r.top + (1 - p.y) / 2 * r.height };
};
phri.capsuleIndex = (link) => view.capsules.findIndex((m) => m.userData.link === link);

// ------------------------------------------------------------------ drag-to-push
const drag = { active: false, body: -1, local: null, plane: new THREE.Plane(), hand: new THREE.Vector3(), sent: 0 };
const raycaster = new THREE.Raycaster();

function pointerRay(event) {
  const r = renderer.domElement.getBoundingClientRect();
  raycaster.setFromCamera(new THREE.Vector2((event.clientX - r.left) / r.width * 2 - 1,
                                            -((event.clientY - r.top) / r.height) * 2 + 1), camera);
}

// The push: proportional to the drag from where the link was grabbed, capped. Not a spring to the
// moving link: with the stream's and the requests' latency (tens of ms) a spring on a compliant
// arm is a delayed feedback loop, and it made the arm swing.
function pushForce() {
  const force = drag.hand.clone().sub(drag.grabbed).multiplyScalar(PUSH_N_PER_M);
  const max = phri.model.push_max_N;
  if (force.length() > max) force.setLength(max);
  return force;
}

function sendPush() {
  if (!drag.active) return;
  drag.sent = performance.now();
  const force = pushForce();
  phri.pushes++;
  $('push-readout').textContent = `pushing ${view.capsules.find((m) => m.userData.body === drag.body)?.userData.link}: ` +
                                  `${force.length().toFixed(1)} N`;
  const body = { body: drag.body, point: drag.local.toArray(), force: force.toArray() };
  pushRenewer.postMessage({ request: { url: new URL('/api/push', location.href).href, init: {
    method: 'POST', headers: { 'Content-Type': 'application/json', 'X-Phri-Token': token }, body: JSON.stringify(body) } } });
  post('push', body);
}

renderer.domElement.addEventListener('pointerdown', (event) => {
  pointerRay(event);
  const hit = raycaster.intersectObjects(view.capsules, false).find((h) => h.object.userData.body >= 0);
  if (!hit) return;
  controls.enabled = false;  // the drag pushes the arm; it does not turn the view
  renderer.domElement.setPointerCapture(event.pointerId);
  Object.assign(drag, { active: true, body: hit.object.userData.body });
  drag.local = view.bodies[drag.body].worldToLocal(hit.point.clone());
  drag.hand.copy(hit.point);
  drag.grabbed = hit.point.clone();
  drag.plane.setFromNormalAndCoplanarPoint(camera.getWorldDirection(new THREE.Vector3()), hit.point);
  $('push-readout').classList.add('active');
  sendPush();
  pushRenewer.postMessage({ start: true, period: PUSH_RENEW_MS });
});

renderer.domElement.addEventListener('pointermove', (event) => {
  if (!drag.active) return;
  pointerRay(event);
  raycaster.ray.intersectPlane(drag.plane, drag.hand);
  if (performance.now() - drag.sent >= 50) sendPush();
});

function release() {
  if (!drag.active) return;
  drag.active = false;
  pushRenewer.postMessage({ stop: true });
  controls.enabled = true;
  $('push-readout').classList.remove('active');
  $('push-readout').textContent = `drag a link to push it (max ${phri.model.push_max_N} N)`;
  post('release');
}
renderer.domElement.addEventListener('pointerup', release);
renderer.domElement.addEventListener('pointercancel', release);

// ------------------------------------------------------------------ plots
const JOINT_COLOURS = ['#e53935', '#fb8c00', '#fdd835', '#43a047', '#00acc1', '#3949ab', '#8e24aa'];
const plots = [];

// A plot: its series are functions of a frame; data kept for the last WINDOW_S of robot time.
function addPlot(title, series, options = {}) {
  const el = document.createElement('div');
  el.id = 'plot-' + title.replace(/[^a-z0-9]+/gi, '-').toLowerCase();
  $('plots').appendChild(el);
  const u = new uPlot({
    title, width: 440, height: 170,
    scales: { x: { time: false }, ...(options.scales || {}) },
    axes: [{ label: 't [s]' }, { label: options.unit || '' }],
    legend: { live: false },
    series: [{ label: 't' }, ...series.map((s) => ({ label: s.label, stroke: s.colour, width: 1.2, dash: s.dash }))],
  }, [[], ...series.map(() => [])], el);
  plots.push({ u, series, data: [[], ...series.map(() => [])] });
}

function jointSeries(name, pick) {
  return JOINT_COLOURS.map((colour, i) => ({ label: `${name}${i + 1}`, colour, value: (f) => pick(f)[i] }));
}

function buildPlots(model) {
  addPlot('end-effector error', [
    { label: 'position mm', colour: '#1e88e5', value: (f) => f.err_pos_mm },
    { label: 'orientation deg', colour: '#e53935', value: (f) => f.err_ori_deg },
  ]);
  addPlot('wrench norm (dual compliance: 8 up / 4 down)', [
    { label: '|wrench|', colour: '#8e24aa', value: (f) => f.wrench_norm },
    { label: 'touch', colour: '#c62828', dash: [4, 4], value: () => model.touch_threshold },
    { label: 'release', colour: '#2e7d32', dash: [4, 4], value: () => model.release_threshold },
  ]);
  addPlot('tau_d (desired) N.m', jointSeries('τd', (f) => f.tau_d));
  addPlot('tau_s (sensed) N.m', jointSeries('τs', (f) => f.tau_s));
  addPlot('|qd| / velocity limit', jointSeries('q', (f) => f.qd_ratio), { scales: { y: { range: [0, 1] } } });
  addPlot('cycle time us', [{ label: 'compute', colour: '#546e7a', value: (f) => f.cycle_us }]);
  addPlot('supervisor state (0 normal, 1 degraded, 2 safe stop)', [
    { label: 'state', colour: '#d84315', value: (f) => f.safety_code },
  ], { scales: { y: { range: [-0.2, 2.2] } } });
}

// One bar per monitored link, full scale 1.5 (the dashed mark: v = v_max of the link's region).
const CONTACT_FULL_SCALE = 1.5;
function buildContact(model) {
  const contact = model.contact || [];
  $('contact-title').hidden = contact.length === 0;
  for (const c of contact) {
    const row = document.createElement('div');
    row.className = 'contact-row';
    row.title = `${c.link} may meet: ${c.region} (ISO/TS 15066 transient contact)`;
    row.innerHTML = `<span>${c.link}</span><div class="contact-bar"><div></div></div><span>-</span>`;
    $('contact').appendChild(row);
  }
}

function showContact(f) {
  const rows = $('contact').children;
  (f.contact_ratio || []).forEach((ratio, i) => {
    if (i >= rows.length) return;
    const bar = rows[i].children[1].firstChild;
    bar.style.width = `${Math.min(100, (100 * ratio) / CONTACT_FULL_SCALE)}%`;
    bar.style.background = `hsl(${Math.max(0, 120 * (1 - ratio))}, 70%, 45%)`;  // green -> red at v_max
    rows[i].children[2].textContent = ratio.toFixed(2);
  });
}

function record(f) {
  for (const p of plots) {
    p.data[0].push(f.t);
    p.series.forEach((s, i) => p.data[i + 1].push(s.value(f)));
    let drop = 0;
    while (drop < p.data[0].length && p.data[0][drop] < f.t - WINDOW_S) drop++;
    if (drop > 0) p.data.forEach((column) => column.splice(0, drop));
  }
}

// Plots and the 3-D view are redrawn when frames arrive (at most every PLOT_PERIOD_MS / VIEW_PERIOD_MS),
// not on timers or animation frames, which a browser throttles when it thinks nobody looks.
const VIEW_PERIOD_MS = 33;
let lastPlot = 0, lastView = 0;
function redraw(now) {
  if (now - lastPlot >= PLOT_PERIOD_MS) {
    lastPlot = now;
    for (const p of plots) p.u.setData(p.data);
    phri.plotUpdates++;
  }
  if (phri.view3d !== false && now - lastView >= VIEW_PERIOD_MS) {
    lastView = now;
    renderer.render(scene, camera);
  }
}
controls.addEventListener('change', () => renderer.render(scene, camera));
phri.plotXMax = () => (plots.length ? plots[0].u.data[0][plots[0].u.data[0].length - 1] ?? null : null);

// ------------------------------------------------------------------ the stream
function showStatus(f) {
  $('status').textContent = `t ${f.t.toFixed(2)} s | ${f.paused ? 'PAUSED' : 'running'} | mode ${f.mode}` +
    `${f.touched ? ' (touched)' : ''} | loop ${f.loop} | fsm ${f.fsm} | safety ${f.safety} | ` +
    `cycle ${f.cycle_us.toFixed(1)} us | overruns ${f.overruns}`;
  for (const [event, mode] of Object.entries(MODE_OF_EVENT)) $('event-' + event)?.classList.toggle('active', f.mode === mode);
  for (const [event, loop] of Object.entries(LOOP_OF_EVENT)) $('event-' + event)?.classList.toggle('active', f.loop === loop);
  $('pause').classList.toggle('active', f.paused);
}

function connect() {
  const stream = new EventSource('/api/stream?token=' + encodeURIComponent(token));
  stream.onmessage = (message) => {
    const f = JSON.parse(message.data);
    phri.frames++;
    phri.last = f;
    record(f);
    showArm(f);
    showStatus(f);
    showGains(f.gains);
    showContact(f);
    redraw(performance.now());
  };
  stream.onerror = () => { $('status').textContent = 'stream lost: is phri still running? (retrying)'; };
}

async function main() {
  const res = await fetch('/api/model?token=' + encodeURIComponent(token));
  if (!res.ok) {
    $('status').textContent = 'refused (' + res.status + '): open the address phri printed, with its token';
    return;
  }
  const model = (phri.model = await res.json());
  $('push-max').textContent = model.push_max_N;
  buildButtons(model);
  buildSliders(model);
  buildArm(model);
  buildPlots(model);
  buildContact(model);
  resize();
  connect();
}
main();
