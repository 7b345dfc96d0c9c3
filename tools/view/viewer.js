// soadyn view: plays a run in 3D (three.js) with linked plots.  The run is the JSON block
// #soadyn-run written by `soadyn view`: the bodies as the model knows them, and per frame the
// pose of every body frame (position of the joint point, orientation body -> world), computed
// by soadyn's kinematics from the logged q.  Nothing here fetches anything.
(function () {
  'use strict';
  const RUN = JSON.parse(document.getElementById('soadyn-run').textContent);

  function decode(text, Type) {
    const bin = atob(text);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }
  const K = RUN.frames.n, NB = RUN.frames.nb, NQ = RUN.nq;
  const T = decode(RUN.frames.t, Float64Array);   // K
  const P = decode(RUN.frames.pose, Float32Array); // K x NB x [px py pz qx qy qz qw]
  const Q = decode(RUN.q, Float32Array);           // K x NQ
  const t0 = T[0], t1 = T[K - 1];

  // --- scene ------------------------------------------------------------------------------------
  const pane = document.getElementById('scene-pane');
  const renderer = new THREE.WebGLRenderer({ antialias: false });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  pane.insertBefore(renderer.domElement, pane.firstChild);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xeef1f5);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8f99, 0.75));
  const sun = new THREE.DirectionalLight(0xffffff, 0.55);
  scene.add(sun);

  const V = (a) => new THREE.Vector3(a[0], a[1], a[2]);
  const g = V(RUN.gravity);
  const up = g.length() > 0 ? g.clone().negate().normalize() : new THREE.Vector3(0, 0, 1);
  const lo = V(RUN.bounds.min), hi = V(RUN.bounds.max);
  const center = lo.clone().add(hi).multiplyScalar(0.5);
  const extent = hi.clone().sub(lo);
  // L: the scene's size, from the whole motion (at least the largest body)
  let L = extent.length();
  RUN.bodies.forEach((b) => { L = Math.max(L, V(b.box.size).length()); });
  if (!(L > 1e-6)) L = 1;
  // sizes of the drawing: from the scene, and no larger than the links allow
  const lengths = [];
  RUN.bodies.forEach((b) => b.segments.forEach((sg) => lengths.push(V(sg).length())));
  lengths.sort((a, b) => a - b);
  const link = lengths.length ? lengths[lengths.length >> 1] : L;
  const rSkel = Math.min(0.012 * L, 0.06 * link), rCmMax = Math.min(0.035 * L, 0.25 * link), arrowLen = Math.min(0.09 * L, 0.5 * link);

  // the model's mesh files, read by three.js's loaders (meshes.js); the bodies: a mesh per layer,
  // skinned to a bone per body (bodies.js)
  const meshFiles = new SoadynMeshes(THREE, RUN.meshes || []);
  const bodies = new SoadynBodies(THREE, scene, RUN, L, rSkel, rCmMax, arrowLen, meshFiles);
  const bones = bodies.bones, layers = bodies.layers, bodyMeshes = bodies.meshes, visualCount = bodies.visualCount;
  // the frames the run logged: a triad each, with its name (frames.js)
  const named = new SoadynNamedFrames(THREE, scene, RUN.named_frames, decode, 0.8 * arrowLen, 0.22 * rSkel);

  // world frame, and a ground grid normal to gravity just below the motion
  const Y = new THREE.Vector3(0, 1, 0);
  scene.add(new THREE.AxesHelper(0.25 * L));
  let low = Infinity;
  for (let c = 0; c < 8; ++c) {
    const corner = new THREE.Vector3(c & 1 ? hi.x : lo.x, c & 2 ? hi.y : lo.y, c & 4 ? hi.z : lo.z);
    low = Math.min(low, corner.dot(up));
  }
  const cell = Math.pow(10, Math.floor(Math.log10(L / 2)));  // a power of ten, L/20 to L/2
  // a 40 x 40 grid of cells, its lines cut in pieces of 5 cells: a software rasterizer may drop a
  // whole line that passes behind the camera (one piece per cell costs a quarter of the frame rate)
  const gridPos = [], gridCol = [], c1 = new THREE.Color(0x9aa3ad), c2 = new THREE.Color(0xc9d0da);
  for (let i = -20; i <= 20; ++i) {
    const col = i === 0 ? c1 : c2;
    for (let j = -20; j < 20; j += 5) {
      gridPos.push(i * cell, 0, j * cell, i * cell, 0, (j + 5) * cell, j * cell, 0, i * cell, (j + 5) * cell, 0, i * cell);
      for (let n = 0; n < 4; ++n) gridCol.push(col.r, col.g, col.b);
    }
  }
  const gridGeom = new THREE.BufferGeometry();
  gridGeom.setAttribute('position', new THREE.Float32BufferAttribute(gridPos, 3));
  gridGeom.setAttribute('color', new THREE.Float32BufferAttribute(gridCol, 3));
  const grid = new THREE.LineSegments(gridGeom, new THREE.LineBasicMaterial({ vertexColors: THREE.VertexColors }));
  grid.quaternion.setFromUnitVectors(Y, up);
  grid.position.copy(center).addScaledVector(up, low - 0.05 * L - center.dot(up));
  scene.add(grid);

  // trail behind a body's centre of mass
  const trailPos = new Float32Array(3 * K);
  const trailGeom = new THREE.BufferGeometry();
  trailGeom.setAttribute('position', new THREE.BufferAttribute(trailPos, 3));
  const trail = new THREE.Line(trailGeom, new THREE.LineBasicMaterial({ color: 0x1d2430 }));
  trail.frustumCulled = false;
  scene.add(trail);
  let trailBody = -1, trailSeconds = 4;
  function setTrailBody(i) {
    trailBody = i;
    const com = i >= 0 ? V(RUN.bodies[i].com) : null;
    const q = new THREE.Quaternion(), p = new THREE.Vector3();
    for (let k = 0; k < K && com; ++k) {
      const o = (k * NB + i) * 7;
      q.set(P[o + 3], P[o + 4], P[o + 5], P[o + 6]);
      p.copy(com).applyQuaternion(q);
      trailPos[3 * k] = P[o] + p.x;
      trailPos[3 * k + 1] = P[o + 1] + p.y;
      trailPos[3 * k + 2] = P[o + 2] + p.z;
    }
    trailGeom.attributes.position.needsUpdate = true;
    trail.visible = i >= 0;
    dirty = true;
  }

  // camera: framing the whole motion, looking along the direction in which it is thinnest
  const camera = new THREE.PerspectiveCamera(40, 1, L * 1e-3, L * 100);
  camera.up.copy(up);
  const axes = [new THREE.Vector3(1, 0, 0), new THREE.Vector3(0, 1, 0), new THREE.Vector3(0, 0, 1)];
  const ext = [extent.x, extent.y, extent.z];
  const thin = ext.indexOf(Math.min.apply(null, ext));
  let view;
  if (ext[thin] < 0.3 * Math.max.apply(null, ext) && Math.abs(axes[thin].dot(up)) < 0.9) {
    const a = axes[thin], side = new THREE.Vector3().crossVectors(up, a);
    view = a.clone().addScaledVector(up, 0.45).addScaledVector(side, 0.3);
  } else {
    const e1 = Math.abs(up.x) < 0.9 ? axes[0].clone() : axes[1].clone();
    e1.addScaledVector(up, -e1.dot(up)).normalize();
    const e2 = new THREE.Vector3().crossVectors(up, e1);
    view = e1.multiplyScalar(1.0).addScaledVector(e2, -0.75).addScaledVector(up, 0.55);
  }
  view.normalize();
  const controls = new THREE.OrbitControls(camera, renderer.domElement);
  controls.enableKeys = false;  // the arrow keys step time
  controls.target.copy(center);
  function frameCamera() {
    const radius = Math.max(0.5 * extent.length(), 0.25 * L);
    const aspect = camera.aspect, half = THREE.Math.degToRad(camera.fov / 2);
    const fit = Math.min(Math.tan(half), Math.tan(half) * aspect);
    camera.position.copy(center).addScaledVector(view, 1.05 * radius / Math.sin(Math.atan(fit)));
    controls.target.copy(center);
    controls.update();
  }
  sun.position.copy(view).multiplyScalar(L).add(up.clone().multiplyScalar(L));
  let dirty = true;
  controls.addEventListener('change', () => { dirty = true; });

  function resize() {
    const w = Math.max(1, pane.clientWidth), h = Math.max(1, pane.clientHeight);
    renderer.setSize(w, h);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    plots.forEach((p) => p.resize());
    dirty = true;
  }

  // --- time -------------------------------------------------------------------------------------
  let t = t0, playing = false, speed = 1;
  const qa = new Float32Array(4);
  // the frame k with T[k] <= t < T[k+1]
  function frameAt(time) {
    let a = 0, b = K - 1;
    if (time <= T[0]) return 0;
    if (time >= T[b]) return b;
    while (b - a > 1) {
      const m = (a + b) >> 1;
      if (T[m] <= time) a = m; else b = m;
    }
    return a;
  }
  // poses at t: positions interpolated linearly, orientations by slerp, between logged frames
  function applyPoses() {
    const k = frameAt(t), k2 = Math.min(k + 1, K - 1);
    const s = T[k2] > T[k] ? Math.min(1, Math.max(0, (t - T[k]) / (T[k2] - T[k]))) : 0;
    for (let i = 0; i < NB; ++i) {
      const o = (k * NB + i) * 7, o2 = (k2 * NB + i) * 7, gi = bones[i];
      gi.position.set(P[o] + s * (P[o2] - P[o]), P[o + 1] + s * (P[o2 + 1] - P[o + 1]), P[o + 2] + s * (P[o2 + 2] - P[o + 2]));
      THREE.Quaternion.slerpFlat(qa, 0, P, o + 3, P, o2 + 3, s);
      gi.quaternion.set(qa[0], qa[1], qa[2], qa[3]);
    }
    named.apply(k, k2, s);
    if (trailBody >= 0) {
      const first = trailSeconds === Infinity ? 0 : frameAt(t - trailSeconds);
      trailGeom.setDrawRange(first, k - first + 1);
    }
    return k;
  }

  const playBtn = document.getElementById('play');
  const slider = document.getElementById('time');
  const tlabel = document.getElementById('tlabel');
  const speedSel = document.getElementById('speed');
  const digits = Math.max(2, Math.min(4, 1 - Math.floor(Math.log10(Math.max(1e-9, (t1 - t0) / Math.max(1, K - 1))))));
  function setPlaying(p) {
    playing = p;
    if (p && t >= t1) t = t0;  // play at the end starts over
    playBtn.innerHTML = p ? '&#10074;&#10074;' : '&#9654;';
    dirty = true;
  }
  function seek(time) {
    t = Math.min(t1, Math.max(t0, time));
    dirty = true;
  }
  function stepFrame(n) {
    setPlaying(false);
    const k = frameAt(t + 1e-9 * (t1 - t0));
    seek(T[Math.min(K - 1, Math.max(0, (n < 0 && T[k] < t - 1e-12 ? k + 1 : k) + n))]);
  }
  function setSpeed(s) {
    speed = s;
    speedSel.value = String(s);
  }
  const speeds = Array.from(speedSel.options).map((o) => Number(o.value));

  playBtn.addEventListener('click', () => setPlaying(!playing));
  slider.addEventListener('input', () => { setPlaying(false); seek(t0 + (t1 - t0) * slider.value / 1e6); });
  speedSel.addEventListener('change', () => setSpeed(Number(speedSel.value)));
  window.addEventListener('keydown', (e) => {
    if (e.target && e.target.tagName === 'SELECT') return;
    const idx = speeds.indexOf(speed);
    if (e.key === ' ') setPlaying(!playing);
    else if (e.key === 'ArrowRight') { if (e.shiftKey) { setPlaying(false); seek(t + 1); } else stepFrame(1); }
    else if (e.key === 'ArrowLeft') { if (e.shiftKey) { setPlaying(false); seek(t - 1); } else stepFrame(-1); }
    else if (e.key === 'ArrowUp') setSpeed(speeds[Math.min(speeds.length - 1, idx + 1)]);
    else if (e.key === 'ArrowDown') setSpeed(speeds[Math.max(0, idx - 1)]);
    else if (e.key === 'Home') { setPlaying(false); seek(t0); }
    else if (e.key === 'End') { setPlaying(false); seek(t1); }
    else if (e.key === 'v' || e.key === 'b') toggleLayer(e.key === 'v' ? 'visuals' : 'boxes');
    else return;
    e.preventDefault();
  });

  // --- plots (plot.js) ---------------------------------------------------------------------------
  const onSeek = (time) => { setPlaying(false); seek(time); };
  const plotEnergy = new SoadynPlot(document.getElementById('plot-energy'), T, onSeek);
  const plotJoint = new SoadynPlot(document.getElementById('plot-joint'), T, onSeek);
  const plots = [plotEnergy, plotJoint];
  plotEnergy.setLabels('time (s)', RUN.energy ? 'relative error (J/J)' : '');
  if (RUN.energy) {
    plotEnergy.y = decode(RUN.energy.error, Float32Array);
    const L = RUN.energy.impacts;
    document.getElementById('energy-title').textContent = RUN.energy.balance
      ? 'energy-balance error (E \u2212 E\u2080 \u2212 W' + (RUN.energy.prescribed ? ' \u2212 W_p' : '') + (L ? ' + L' : '') +
        ') / max(|E\u2080|, peak T), W the work of torques and dampers' +
        (RUN.energy.prescribed ? ', W_p the prescribed joints\u2019 torques\u2019' : '') +
        (L ? ', L the energy the limits\u2019 impacts took' : '')
      : 'energy error (E \u2212 E\u2080) / max(|E\u2080|, peak T)' + (RUN.energy.work_inputs ? ': inputs do work, E is not conserved' : '');
  } else {
    document.getElementById('energy-title').textContent = 'energy: not in this run file';
  }
  const coordSel = document.getElementById('coord');
  // every q coordinate with its unit (rad, m, or 1 for a quaternion's parts), and for a joint with
  // a unit quaternion its rotation angle 2 acos|q_w|
  const units = RUN.coord_units || [];
  const series = RUN.coords.map((name, c) => ({ name: name, unit: units[c] || '?', at: (k) => Q[k * NQ + c] }));
  RUN.bodies.forEach((b) => {
    const w = b.quaternion >= 0 ? b.iq + b.quaternion : -1;  // q_w of the joint's unit quaternion
    if (w >= 0) series.push({ name: b.joint + ' rotation angle', unit: 'rad', angle: true, at: (k) => 2 * Math.acos(Math.min(1, Math.abs(Q[k * NQ + w]))) });
  });
  const titled = (sr) => sr.name + ' (' + sr.unit + ')';
  series.forEach((sr, c) => { const o = document.createElement('option'); o.value = c; o.textContent = titled(sr); coordSel.appendChild(o); });
  function setCoord(c) {
    const y = new Float32Array(K);
    for (let k = 0; k < K; ++k) y[k] = series[c].at(k);
    coordSel.value = String(c);
    plotJoint.setLabels('time (s)', titled(series[c]));
    plotJoint.set(y);
    dirty = true;
  }

  // --- the joint limits' events: marks over the slider and on both plots, and a list; a click seeks
  const events = RUN.events || [];
  const marks = document.getElementById('event-marks');
  const markOf = [];
  if (events.length) {
    const lost = events.reduce((a, e) => a + (e.energy_lost || 0), 0);
    document.getElementById('events-box').style.display = 'block';
    document.getElementById('events-title').textContent = events.length + ' joint-limit event' + (events.length > 1 ? 's' : '') +
      (lost > 0 ? ' (impacts took ' + lost.toPrecision(3) + ' J)' : '');
    const list = document.getElementById('events-list');
    const shown = Math.min(events.length, 200);  // the marks show all; the list the first 200
    events.forEach((e, j) => {
      const what = 't = ' + e.t.toPrecision(9) + ' s \u00b7 ' + e.joint + ' at its ' + e.side + ' limit \u00b7 ' + e.kind +
        (e.kind === 'impact' ? ', v ' + Number(e.v_before).toPrecision(3) + ' \u2192 ' + Number(e.v_after).toPrecision(3) : '');
      const mark = document.createElement('div');
      mark.className = 'event-mark';
      mark.style.left = (100 * (e.t - t0) / Math.max(1e-300, t1 - t0)) + '%';
      mark.title = what;
      mark.addEventListener('click', () => onSeek(e.t));
      marks.appendChild(mark);
      markOf.push(mark);
      if (j < shown) {
        const row = document.createElement('div');
        row.className = 'event-row';
        row.textContent = what;
        row.addEventListener('click', () => onSeek(e.t));
        list.appendChild(row);
      }
    });
    if (shown < events.length) list.appendChild(document.createTextNode('\u2026 and ' + (events.length - shown) + ' more (marked on the timeline)'));
    const times = events.map((e) => e.t);
    plots.forEach((p) => { p.marks = times; });
  }

  // --- options ----------------------------------------------------------------------------------
  // a model with visuals is drawn in them, its inertia boxes hidden until asked for (key b);
  // without, in its inertia boxes
  const hasVisuals = visualCount + bodies.meshCount + bodies.fellBack.length > 0;
  const layerBox = {};
  function showLayer(layer, on) {
    layerBox[layer].checked = on;
    layers[layer].forEach((o) => { o.visible = on; });
    dirty = true;
  }
  function toggleLayer(layer) { showLayer(layer, !layerBox[layer].checked); }
  [['show-skeleton', 'skeleton'], ['show-boxes', 'boxes'], ['show-visuals', 'visuals'], ['show-axes', 'axes']].forEach(([id, layer]) => {
    const box = document.getElementById(id);
    layerBox[layer] = box;
    if (layer === 'visuals' && !hasVisuals) box.parentNode.style.display = 'none';
    box.addEventListener('change', () => showLayer(layer, box.checked));
  });
  showLayer('boxes', !hasVisuals);
  const framesBox = document.getElementById('show-frames');
  if (named.F === 0) document.getElementById('named-frames-box').style.display = 'none';
  framesBox.addEventListener('change', () => { named.group.visible = framesBox.checked; dirty = true; });
  const trailSel = document.getElementById('trail-body');
  RUN.bodies.forEach((b, i) => { const o = document.createElement('option'); o.value = i; o.textContent = b.name; trailSel.appendChild(o); });
  trailSel.addEventListener('change', () => setTrailBody(Number(trailSel.value)));
  const trailLen = document.getElementById('trail-length');
  trailLen.addEventListener('change', () => { trailSeconds = Number(trailLen.value); trail.visible = trailSeconds > 0; dirty = true; });

  document.getElementById('name').textContent = RUN.name;
  document.getElementById('desc').textContent = RUN.description;
  document.getElementById('meta').textContent = RUN.run + ' \u00b7 ' + NB + ' bodies \u00b7 ' + (RUN.method || '?') +
    (RUN.status && RUN.status !== 'completed' ? ' \u00b7 ' + RUN.status : '') + ' \u00b7 soadyn ' + RUN.version;
  // the mesh files that could not be drawn, each named with the reason (the file's, or its loader's)
  const badMeshes = meshFiles.files.filter((f) => f.error);
  const fellBack = bodies.fellBack.map((i) => RUN.bodies[i].name);
  const meshNote = badMeshes.length === 0 ? '' : '  ' + badMeshes.length + ' mesh file(s) not drawn' +
    (fellBack.length ? ' (' + fellBack.join(', ') + ' drawn in the default shape, the inertia box, instead)' : '') + ': ' +
    badMeshes.map((f) => f.name + ': ' + f.error).join('; ') + '.';
  document.getElementById('frames-note').textContent = 'frames: ' + RUN.frames.rule + '; poses in between are interpolated.' + meshNote +
    (named.F ? '  Logged frames (x red, y green, z blue): ' + named.names.map((n, j) => n + ' on ' + named.bodies[j]).join(', ') + '.' : '');

  // picking: a click (not a drag) on a body puts the trail behind it (the body drawn there, else
  // the one whose centre of mass is drawn nearest, within 30 px)
  const raycaster = new THREE.Raycaster();
  const pointer = new THREE.Vector2();
  let downAt = null;
  renderer.domElement.addEventListener('pointerdown', (e) => { downAt = [e.clientX, e.clientY]; });
  renderer.domElement.addEventListener('pointerup', (e) => {
    if (!downAt || Math.hypot(e.clientX - downAt[0], e.clientY - downAt[1]) > 4) return;
    const r = renderer.domElement.getBoundingClientRect();
    pointer.set((e.clientX - r.left) / r.width * 2 - 1, -(e.clientY - r.top) / r.height * 2 + 1);
    raycaster.setFromCamera(pointer, camera);
    const hit = bodies.pick(raycaster.ray);
    let i = hit ? hit.body : -1, best = hit ? -1 : 30 * 30;
    const c = new THREE.Vector3();
    bones.forEach((bone, j) => {
      c.fromArray(RUN.bodies[j].com).applyMatrix4(bone.matrixWorld).project(camera);
      const dx = (c.x - pointer.x) * r.width / 2, dy = (c.y - pointer.y) * r.height / 2;
      if (c.z < 1 && dx * dx + dy * dy < best) { best = dx * dx + dy * dy; i = j; }
    });
    if (i >= 0) { trailSel.value = String(i); setTrailBody(i); }
  });

  // hovering: the name of the body drawn under the pointer, in a label beside it (looked up once
  // per frame at most, on the poses last drawn)
  const hoverLabel = document.getElementById('hover-label');
  let hoverAt = null;
  renderer.domElement.addEventListener('pointermove', (e) => {
    if (hoverAt === null) requestAnimationFrame(hover);
    hoverAt = [e.clientX, e.clientY];
  });
  renderer.domElement.addEventListener('pointerleave', () => { hoverAt = null; hoverLabel.style.display = 'none'; });
  function hover() {
    if (hoverAt === null) return;
    const r = renderer.domElement.getBoundingClientRect(), pr = pane.getBoundingClientRect();
    pointer.set((hoverAt[0] - r.left) / r.width * 2 - 1, -(hoverAt[1] - r.top) / r.height * 2 + 1);
    raycaster.setFromCamera(pointer, camera);
    const hit = bodies.pick(raycaster.ray);
    if (hit) {
      hoverLabel.textContent = RUN.bodies[hit.body].name;
      hoverLabel.style.left = (hoverAt[0] - pr.left + 14) + 'px';
      hoverLabel.style.top = (hoverAt[1] - pr.top + 10) + 'px';
      hoverLabel.style.display = 'block';
    } else {
      hoverLabel.style.display = 'none';
    }
    hoverAt = null;
  }

  // --- URL fragment: #t=1.5 opens paused at t = 1.5 s ------------------------------------------
  function fromHash() {
    const m = /(?:^#|&)t=([-+0-9.eE]+)/.exec(window.location.hash);
    if (m && isFinite(Number(m[1]))) { setPlaying(false); seek(Number(m[1])); return true; }
    return false;
  }
  window.addEventListener('hashchange', fromHash);

  // --- the loop ---------------------------------------------------------------------------------
  let last = null, lastLabel = -1e9;
  // renders: frames drawn; cost: milliseconds spent in each part of drawing them (summed)
  const api = { ready: false, renders: 0, renderedT: null, renderedFrame: -1, cost: { poses: 0, render: 0, plots: 0 } };
  function loop(now) {
    requestAnimationFrame(loop);
    const dt = last === null ? 0 : Math.min(0.25, (now - last) / 1000);
    last = now;
    if (playing) {
      t += dt * speed;
      if (t >= t1) { t = t1; setPlaying(false); }
      dirty = true;
    }
    if (!dirty) return;
    dirty = false;
    const c0 = performance.now();
    const k = applyPoses();
    const c1 = performance.now();
    renderer.render(scene, camera);
    const c2 = performance.now();
    // the slider and the label repaint their part of the page: at most 15 times a second in play
    if (!playing || now - lastLabel > 66) {
      lastLabel = now;
      slider.value = String(Math.round(1e6 * (t - t0) / Math.max(1e-300, t1 - t0)));
      tlabel.textContent = 't = ' + t.toFixed(digits) + ' s / ' + t1.toFixed(digits) + ' s';
    }
    plots.forEach((p) => p.cursor(t, k));
    const c3 = performance.now();
    api.cost.poses += c1 - c0; api.cost.render += c2 - c1; api.cost.plots += c3 - c2;
    api.renders += 1;
    api.renderedT = t;
    api.renderedFrame = k;
  }

  window.addEventListener('resize', resize);
  resize();
  frameCamera();
  const freeRoot = RUN.bodies.findIndex((b) => b.type === 'free' && b.parent < 0);
  const defaultTrail = freeRoot >= 0 ? freeRoot : NB - 1;
  trailSel.value = String(defaultTrail);
  setTrailBody(defaultTrail);
  const firstCoord = RUN.bodies.findIndex((b) => b.type === 'revolute' || b.type === 'prismatic' || b.type === 'helical');
  const angle = series.findIndex((sr) => sr.angle);
  setCoord(firstCoord >= 0 ? RUN.bodies[firstCoord].iq : Math.max(0, angle));
  coordSel.addEventListener('change', () => setCoord(Number(coordSel.value)));
  plotEnergy.draw();
  if (!fromHash()) setPlaying(true);
  // for tests and scripts: playback state and control
  api.seek = (time) => { setPlaying(false); seek(time); };
  api.play = () => setPlaying(true);
  api.pause = () => setPlaying(false);
  api.setSpeed = setSpeed;
  api.showBodies = (on) => { bodyMeshes.forEach((m) => { m.visible = on; }); dirty = true; };
  api.setTrailSeconds = (s) => { trailSeconds = s; trail.visible = s > 0 && trailBody >= 0; dirty = true; };
  api.plotArea = (which) => {
    const p = which === 'joint' ? plotJoint : plotEnergy, r = p.canvas.getBoundingClientRect();
    return { left: r.left + p.left, top: r.top + p.top, w: p.w, h: p.h };
  };
  // the events as drawn: time, joint, kind, and the page x of the mark on the timeline
  api.events = () => events.map((e, j) => {
    const r = markOf[j].getBoundingClientRect();
    return { t: e.t, joint: e.joint, side: e.side, kind: e.kind, x: r.left + r.width / 2, y: r.top + r.height / 2 };
  });
  api.timeline = () => { const r = slider.getBoundingClientRect(); return { left: r.left, width: r.width }; };
  api.counts = () => ({ bodies: NB, frames: K, visuals: visualCount, meshes: bodies.meshCount, meshFiles: meshFiles.files.length,
    meshErrors: badMeshes.map((f) => f.name + ': ' + f.error), fellBack: bodies.fellBack.slice(), trailBody: trailBody, namedFrames: named.F });
  // the layers (skeleton, cm, boxes, visuals, axes): which are shown, and showing or hiding one
  api.layers = () => { const o = {}; Object.keys(layers).forEach((k) => { o[k] = layers[k].every((m) => m.visible); }); return o; };
  api.showLayer = (layer, on) => { if (layerBox[layer]) showLayer(layer, on); else { layers[layer].forEach((m) => { m.visible = on; }); dirty = true; } };
  // the body drawn at page pixel (x, y), or -1 (what hovering there names)
  api.bodyAt = (x, y) => {
    const r = renderer.domElement.getBoundingClientRect();
    raycaster.setFromCamera(new THREE.Vector2((x - r.left) / r.width * 2 - 1, -(y - r.top) / r.height * 2 + 1), camera);
    const hit = bodies.pick(raycaster.ray);
    return hit ? hit.body : -1;
  };
  api.namedFrames = () => named.state();
  api.showNamedFrames = (on) => { named.group.visible = on; framesBox.checked = on; dirty = true; };
  // where body i's centre of mass is drawn, in page pixels; the camera's position and target
  api.screenOf = (i) => {
    const c = new THREE.Vector3().fromArray(RUN.bodies[i].com).applyMatrix4(bones[i].matrixWorld).project(camera);
    const r = renderer.domElement.getBoundingClientRect();
    return { x: r.left + (c.x + 1) / 2 * r.width, y: r.top + (1 - c.y) / 2 * r.height };
  };
  api.camera = () => ({ position: camera.position.toArray(), target: controls.target.toArray() });
  api.state = () => ({ t: t, playing: playing, speed: speed, frames: K, bodies: NB, t0: t0, t1: t1 });
  window.soadynView = api;
  requestAnimationFrame(loop);
  api.ready = true;
})();
