// The page script of `jointsim view` (report/view.hpp, docs/view.md). Reads the page's JSON data, builds the 3D arm
// (three.js), the plots (uPlot), the joint gauges, the run list of a sweep and the summary. Every data-derived text
// goes into the page through textContent, never as markup. window.jointsimView is the script interface the browser
// tests drive: setTime(t), time(), selectRun(i), selectFigure(i), tcpPosition(), readout(k), panels(), errors.
(function () {
  'use strict';
  const errors = [];
  const api = { errors: errors, ready: false };
  window.jointsimView = api;
  function report(msg) {
    errors.push(String(msg));
    const box = document.getElementById('errors');
    box.hidden = false;
    box.textContent = errors.join('\n');
  }
  window.addEventListener('error', function (e) { report('script error: ' + e.message); });

  const D = JSON.parse(document.getElementById('jointsim-data').textContent);
  // Samples against time carry indices into their run's time array ("xi"): resolved here once.
  for (const run of D.runs) {
    const T = run.time || [];
    const times = function (xi) { return xi.map(function (i) { return T[i]; }); };
    for (const f of run.figures || []) for (const p of f.panels) for (const s of p.series) if (s.xi) s.x = times(s.xi);
    if (run.motion) run.motion.t = times(run.motion.xi);
    if (run.key && run.key.xi) run.key.x = times(run.key.xi);
  }
  api.data = D;

  function el(tag, cls, text) {
    const e = document.createElement(tag);
    if (cls) e.className = cls;
    if (text !== undefined && text !== null) e.textContent = String(text);
    return e;
  }
  function fmt(v, digits) {
    if (v === null || v === undefined || !isFinite(v)) return 'n/a';
    const a = Math.abs(v);
    if (Number.isInteger(v) && a < 1e15) return String(v);
    if (a !== 0 && (a >= 1e5 || a < 1e-3)) return v.toExponential((digits || 5) - 1);
    return Number(v.toPrecision(digits || 5)).toString();
  }
  // Index of the last element of the sorted array `xs` that is <= x (-1 if none).
  function lastAtOrBefore(xs, x) {
    let lo = 0, hi = xs.length - 1, k = -1;
    while (lo <= hi) {
      const m = (lo + hi) >> 1;
      if (xs[m] !== null && xs[m] <= x) { k = m; lo = m + 1; } else hi = m - 1;
    }
    return k;
  }
  const COLORS = ['#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#8c564b', '#e377c2', '#7f7f7f', '#bcbd22',
                  '#17becf'];

  const state = { run: 0, t: 0, t0: 0, t1: 0, playing: false, speed: 1, figure: 0, charts: [], overlay: null,
                  syncing: false, last: 0 };

  // ---------------------------------------------------------------------------------------------- header, notes
  document.getElementById('title').textContent = D.title;
  document.getElementById('subtitle').textContent =
      D.kind === 'sweep' ? 'sweep of ' + D.runs.length + ' runs' : (D.runs[0].type || '') + ' run';

  function showNotes(run) {
    const box = document.getElementById('notes');
    box.replaceChildren();
    const notes = [];
    if (!D.arm && D.arm_note) notes.push('No 3D view: ' + D.arm_note + '.');
    for (const n of D.notes || []) notes.push(n);
    if (run && run.motion_note) notes.push('No motion for this run: ' + run.motion_note + '.');
    if (run && run.error) notes.push('This run has no log: ' + run.error);
    if (run && run.changed_inputs && run.changed_inputs.length)
      notes.push('Changed since the run (the arm is drawn from the files as they are now): ' +
                 run.changed_inputs.join(', '));
    if (D.kind === 'sweep') notes.push('Figures of one run: jointsim view on its run folder.');
    for (const n of notes) box.appendChild(el('div', 'note', n));
  }

  function summaryTree(value, key, depth) {
    if (value !== null && typeof value === 'object') {
      const entries = Array.isArray(value) ? value.map(function (v, i) { return [String(i), v]; })
                                           : Object.keys(value).map(function (k) { return [k, value[k]]; });
      const scalars = Array.isArray(value) && entries.every(function (e) { return e[1] === null || typeof e[1] !== 'object'; });
      if (scalars) {
        const shown = value.slice(0, 40).map(function (v) { return typeof v === 'number' ? fmt(v, 6) : String(v); });
        const row = el('div', 'kv');
        row.appendChild(el('span', 'k', key + ': '));
        row.appendChild(el('span', 'v', '[' + shown.join(', ') + (value.length > 40 ? ', … (' + value.length + ')' : '') + ']'));
        return row;
      }
      const d = el('details');
      if (depth < 1) d.open = true;
      d.appendChild(el('summary', null, key));
      for (const [k, v] of entries.slice(0, 500)) d.appendChild(summaryTree(v, k, depth + 1));
      return d;
    }
    const row = el('div', 'kv');
    row.appendChild(el('span', 'k', key + ': '));
    row.appendChild(el('span', 'v', typeof value === 'number' ? fmt(value, 8) : String(value)));
    return row;
  }
  function showSummary(run) {
    const box = document.getElementById('summary');
    box.replaceChildren();
    const s = run.summary || {};
    const status = document.getElementById('status');
    status.textContent = String(run.status || s.status || '?');
    status.className = (run.status || s.status) === 'ok' ? '' : 'bad';
    for (const k of Object.keys(s)) box.appendChild(summaryTree(s[k], k, 0));
  }

  // ------------------------------------------------------------------------------------------------ the 3D arm
  const arm = { ok: false };
  function vec(a) { return new THREE.Vector3(a[0], a[1], a[2]); }
  function placement(obj, o) {
    const R = o.R, m = new THREE.Matrix4();
    m.set(R[0], R[1], R[2], o.p[0], R[3], R[4], R[5], o.p[1], R[6], R[7], R[8], o.p[2], 0, 0, 0, 1);
    m.decompose(obj.position, obj.quaternion, obj.scale);
  }
  // A cylinder from a to b (in the frame of `parent`).
  function rod(parent, a, b, radius, material) {
    const d = new THREE.Vector3().subVectors(b, a), len = d.length();
    if (len < 1e-9) return;
    const g = new THREE.CylinderBufferGeometry(radius, radius, len, 16);
    const mesh = new THREE.Mesh(g, material);
    mesh.position.copy(a).addScaledVector(d, 0.5);
    mesh.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), d.clone().normalize());
    parent.add(mesh);
  }
  function buildArm() {
    const A = D.arm, box = document.getElementById('scene'), note = document.getElementById('scene-note');
    if (!A) {
      note.hidden = false;
      note.textContent = 'No 3D view: ' + (D.arm_note || 'this run has no arm') + '.';
      return;
    }
    const scene = new THREE.Scene();
    scene.background = new THREE.Color(0xeef1f5);
    const base = new THREE.Group();
    scene.add(base);
    let reach = 0;
    for (const j of A.joints) reach += Math.hypot(j.origin.p[0], j.origin.p[1], j.origin.p[2]);
    reach += Math.hypot(A.tcp.origin.p[0], A.tcp.origin.p[1], A.tcp.origin.p[2]);
    reach = Math.max(reach, 0.1);
    const r = reach * 0.02;
    const linkMat = new THREE.MeshLambertMaterial({ color: 0x9aa7b8 });
    const jointMat = new THREE.MeshLambertMaterial({ color: 0x1f77b4 });
    const tcpMat = new THREE.MeshLambertMaterial({ color: 0xff7f0e });
    const moving = [];
    // With link geometry from the robot file (URDF <visual>), that is drawn instead of the simple links.
    const simple = !(A.visuals && A.visuals.length);
    A.joints.forEach(function (j, i) {
      const fixed = new THREE.Object3D();
      placement(fixed, j.origin);
      const parent = j.parent >= 0 ? moving[j.parent] : base;
      parent.add(fixed);
      if (simple) rod(parent, new THREE.Vector3(), vec(j.origin.p), r, linkMat);
      const mov = new THREE.Object3D();
      fixed.add(mov);
      moving.push(mov);
      const ax = vec(j.axis).normalize();
      if (!simple) return;
      if (j.prismatic) rod(fixed, ax.clone().multiplyScalar(-2 * r), ax.clone().multiplyScalar(2 * r), 1.2 * r, jointMat);
      else rod(fixed, ax.clone().multiplyScalar(-1.6 * r), ax.clone().multiplyScalar(1.6 * r), 1.6 * r, jointMat);
      void i;
    });
    const tcpParent = A.tcp.joint >= 0 ? moving[A.tcp.joint] : base;
    const tcp = new THREE.Object3D();
    placement(tcp, A.tcp.origin);
    tcpParent.add(tcp);
    if (simple) rod(tcpParent, new THREE.Vector3(), vec(A.tcp.origin.p), 0.7 * r, linkMat);
    const visuals = [];
    for (const v of A.visuals || []) {
      const obj = new THREE.Object3D();
      placement(obj, v.origin);
      (v.joint >= 0 ? moving[v.joint] : base).add(obj);
      const rgba = v.rgba || [0.62, 0.68, 0.76, 1];
      const mat = new THREE.MeshLambertMaterial({ color: new THREE.Color(rgba[0], rgba[1], rgba[2]),
                                                  transparent: rgba[3] < 1, opacity: rgba[3] });
      const shape = visualObject(v, mat);
      if (shape) obj.add(shape);
      visuals.push({ link: v.link, object: obj, shape: shape });
    }
    tcp.add(new THREE.Mesh(new THREE.SphereBufferGeometry(1.4 * r, 16, 12), tcpMat));
    tcp.add(new THREE.AxesHelper(5 * r));
    const plate = new THREE.Mesh(new THREE.CylinderBufferGeometry(4 * r, 4 * r, r, 24), linkMat);
    plate.rotation.x = Math.PI / 2;
    plate.position.z = -r / 2;
    base.add(plate);
    const grid = new THREE.GridHelper(2.4 * reach, 24, 0xb8c0cc, 0xd5dae2);
    grid.rotation.x = Math.PI / 2;
    scene.add(grid);
    scene.add(new THREE.AxesHelper(0.3 * reach));
    scene.add(new THREE.AmbientLight(0xffffff, 0.55));
    const sun = new THREE.DirectionalLight(0xffffff, 0.7);
    sun.position.set(1, -2, 3);
    scene.add(sun);
    const camera = new THREE.PerspectiveCamera(40, 1, reach / 100, reach * 50);
    camera.up.set(0, 0, 1);
    camera.position.set(0.95 * reach, -1.25 * reach, 0.8 * reach);
    Object.assign(arm, { ok: true, scene: scene, camera: camera, moving: moving, tcp: tcp, r: r, reach: reach,
                         visuals: visuals, base: base,
                         pathLine: null, clamp: null, renderer: null });
    try {
      const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
      renderer.setPixelRatio(window.devicePixelRatio || 1);
      box.appendChild(renderer.domElement);
      arm.renderer = renderer;
      const controls = new THREE.OrbitControls(camera, renderer.domElement);
      controls.target.set(0, 0, 0.25 * reach);
      controls.addEventListener('change', render);
      controls.update();
      arm.controls = controls;
      new ResizeObserver(resize).observe(box);
      resize();
    } catch (e) {
      note.hidden = false;
      note.textContent = 'WebGL is not available in this browser: the arm is not drawn (its kinematics still follow ' +
                         'the time; ' + e.message + ').';
    }
  }
  function bytesOf(b64) {
    const s = atob(b64), a = new Uint8Array(s.length);
    for (let i = 0; i < s.length; ++i) a[i] = s.charCodeAt(i);
    return a;
  }
  // The three.js object of one URDF visual (its geometry in the visual's frame).
  function visualObject(v, mat) {
    const s = v.size;
    if (v.shape === 'box') return new THREE.Mesh(new THREE.BoxBufferGeometry(s[0], s[1], s[2]), mat);
    if (v.shape === 'sphere') return new THREE.Mesh(new THREE.SphereBufferGeometry(s[0], 24, 16), mat);
    if (v.shape === 'cylinder') {  // URDF cylinders lie along z, three.js's along y
      const m = new THREE.Mesh(new THREE.CylinderBufferGeometry(s[0], s[0], s[1], 24), mat);
      m.rotation.x = Math.PI / 2;
      return m;
    }
    if (v.shape !== 'mesh' || !v.data) return null;
    const bytes = bytesOf(v.data);
    let obj;
    try {
      if (v.format === 'stl') {
        const g = new THREE.STLLoader().parse(bytes.buffer);
        g.computeVertexNormals();  // many STL writers leave the facet normals zero
        obj = new THREE.Mesh(g, mat);
      } else if (v.format === 'obj') {
        obj = new THREE.OBJLoader().parse(new TextDecoder().decode(bytes));
        obj.traverse(function (o) { if (o.isMesh && v.rgba) o.material = mat; });
      } else if (v.format === 'dae') {
        const collada = new THREE.ColladaLoader().parse(new TextDecoder().decode(bytes), '');
        obj = collada.scene;
        obj.quaternion.identity();  // URDF uses the file's own axes (the loader turns Z_UP files to three.js's Y_UP)
        if (v.rgba) obj.traverse(function (o) { if (o.isMesh) o.material = mat; });
      }
    } catch (e) {
      report('mesh ' + v.mesh + ' of link ' + v.link + ' could not be read: ' + e.message);
      return null;
    }
    if (!obj) return null;
    const holder = new THREE.Object3D();
    holder.scale.set(s[0], s[1], s[2]);
    holder.add(obj);
    return holder;
  }
  function resize() {
    if (!arm.renderer) return;
    const box = document.getElementById('scene');
    const w = Math.max(box.clientWidth, 10), h = Math.max(box.clientHeight, 10);
    arm.renderer.setSize(w, h);
    arm.camera.aspect = w / h;
    arm.camera.updateProjectionMatrix();
    render();
  }
  function render() {
    if (arm.renderer) arm.renderer.render(arm.scene, arm.camera);
  }
  function showRunGeometry(run) {
    if (!arm.ok) return;
    if (arm.pathLine) { arm.scene.remove(arm.pathLine); arm.pathLine = null; }
    if (arm.clamp) { arm.scene.remove(arm.clamp); arm.clamp = null; }
    const m = run.motion;
    if (!m) return;
    const pts = (m.tcp_path || []).map(vec);
    if (pts.length > 1) {
      const g = new THREE.BufferGeometry().setFromPoints(pts);
      arm.pathLine = new THREE.Line(g, new THREE.LineBasicMaterial({ color: 0xff7f0e }));
      arm.scene.add(arm.pathLine);
    }
    if (!arm.framed && pts.length) frameCamera(pts);
    if (m.clamp) {
      const s = 5 * arm.r;
      arm.clamp = new THREE.Mesh(new THREE.BoxBufferGeometry(s, s, s),
                                 new THREE.MeshLambertMaterial({ color: 0xd62728, transparent: true, opacity: 0.45 }));
      arm.clamp.position.copy(vec(m.clamp));
      arm.scene.add(arm.clamp);
    }
  }
  // Points the camera once at the arm's workspace of the first run shown: the base and the TCP's path.
  function frameCamera(pts) {
    arm.framed = true;
    if (!arm.controls) return;
    const box = new THREE.Box3().setFromPoints(pts.concat([new THREE.Vector3(0, 0, 0)]));
    const c = box.getCenter(new THREE.Vector3());
    const radius = Math.max(0.5 * box.getSize(new THREE.Vector3()).length(), 0.35 * arm.reach);
    const dist = 1.15 * radius / Math.sin(0.5 * arm.camera.fov * Math.PI / 180);
    arm.controls.target.copy(c);
    arm.camera.position.copy(c).addScaledVector(new THREE.Vector3(1, -1.3, 0.75).normalize(), dist);
    arm.controls.update();
  }
  // Joint angles of the current run at time t: linear between the logged samples (exact at a sample).
  function anglesAt(run, t) {
    const m = run.motion;
    if (!m) return null;
    const ts = m.t;
    let k = lastAtOrBefore(ts, t);
    if (k < 0) k = 0;
    const q = [];
    for (const col of m.q) {
      // Between the finite samples around t (a non-finite angle is skipped); the nearest one outside them.
      let i = k, j = k + 1;
      while (i >= 0 && col[i] === null) --i;
      while (j < ts.length && col[j] === null) ++j;
      if (i < 0 && j >= ts.length) q.push(null);
      else if (i < 0) q.push(col[j]);
      else if (j >= ts.length || t <= ts[i] || ts[j] === ts[i]) q.push(col[i]);
      else q.push(col[i] + (col[j] - col[i]) * Math.min(1, (t - ts[i]) / (ts[j] - ts[i])));
    }
    return q;
  }
  function poseArm(q) {
    if (!arm.ok) return;
    arm.base.visible = !!q;  // a run without motion: no arm drawn
    if (!q) { render(); return; }
    D.arm.joints.forEach(function (j, i) {
      const v = q[i] === null || !isFinite(q[i]) ? 0 : q[i];
      const ax = vec(j.axis).normalize();
      if (j.prismatic) arm.moving[i].position.copy(ax.multiplyScalar(v));
      else arm.moving[i].quaternion.setFromAxisAngle(ax, v);
    });
    arm.scene.updateMatrixWorld(true);
    render();
  }

  // ------------------------------------------------------------------------------------------- joint gauges
  const gauges = [];
  function buildGauges(run) {
    const box = document.getElementById('joints');
    box.replaceChildren();
    gauges.length = 0;
    if (!D.arm || !run.motion) return;
    D.arm.joints.forEach(function (j, i) {
      let lo = j.lower, hi = j.upper, limited = lo !== null && hi !== null;
      if (!limited) {
        lo = 0;
        hi = 0;
        for (const v of run.motion.q[i]) if (v !== null) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
        if (hi - lo < 1e-6) { lo -= 0.1; hi += 0.1; }
      }
      const row = el('div', 'joint');
      row.appendChild(el('span', 'name', j.name));
      const bar = el('div', 'bar' + (limited ? '' : ' nolimits'));
      bar.title = limited ? 'limits ' + fmt(lo) + ' … ' + fmt(hi) + (j.prismatic ? ' m' : ' rad')
                          : 'no limits in the model: the bar spans the logged range';
      const mark = el('div', 'mark');
      bar.appendChild(mark);
      row.appendChild(bar);
      const value = el('span', 'value');
      row.appendChild(value);
      box.appendChild(row);
      gauges.push({ lo: lo, hi: hi, limited: limited, bar: bar, mark: mark, value: value, prismatic: j.prismatic });
    });
  }
  function showGauges(q) {
    if (!q) return;
    gauges.forEach(function (g, i) {
      const v = q[i];
      const f = v === null ? 0 : Math.min(1, Math.max(0, (v - g.lo) / (g.hi - g.lo)));
      g.mark.style.left = 'calc(' + (100 * f).toFixed(2) + '% - 1px)';
      g.bar.classList.toggle('outside', g.limited && v !== null && (v < g.lo || v > g.hi));
      g.value.textContent = g.prismatic ? fmt(v) + ' m' : fmt(v) + ' rad (' + fmt(v * 180 / Math.PI, 4) + '°)';
    });
  }

  // ------------------------------------------------------------------------------------------------- plots
  function plotWidth() {
    return Math.max(300, document.getElementById('plots').clientWidth - 10);
  }
  // Union of the series' x values (sorted), and each series on it: undefined where it has no sample (uPlot joins
  // across those), null where its value is not finite (a gap in the line).
  function aligned(series) {
    const set = new Set();
    for (const s of series) for (const x of s.x) if (x !== null) set.add(x);
    const xs = Array.from(set).sort(function (a, b) { return a - b; });
    const at = new Map(xs.map(function (x, i) { return [x, i]; }));
    const ys = series.map(function (s) {
      const y = new Array(xs.length).fill(undefined);
      s.x.forEach(function (x, i) { if (x !== null) y[at.get(x)] = s.y[i]; });
      return y;
    });
    return [xs].concat(ys);
  }
  function seriesOpts(s, i, emphasis) {
    const o = { label: s.title || s.y_col || 'series ' + (i + 1), stroke: COLORS[i % COLORS.length], width: 1.25,
                spanGaps: false, scale: s.y2 ? 'y2' : 'y', points: { show: false } };
    if (s.style === 1) o.dash = [6, 4];
    if (s.style === 2) { o.stroke = '#000'; o.width = 2.2; }
    if (s.style === 5 || s.style === 6) {
      o.paths = function () { return null; };
      o.points = { show: true, size: s.style === 6 ? 7 : 3, fill: s.style === 6 ? '#d62728' : '#888' };
    }
    if (emphasis !== undefined) {  // a sweep's overlay: the selected run red and bold, the others grey
      o.width = emphasis ? 2.6 : 1;
      o.stroke = emphasis ? '#d62728' : '#a4adba';
      if (o.points.show) o.points.fill = emphasis ? '#d62728' : '#a4adba';
    }
    return o;
  }
  // The readout of a time panel at time t: per series its drawn sample nearest to t (a row of the CSV).
  function readoutAt(panel, t) {
    return panel.series.map(function (s) {
      let k = lastAtOrBefore(s.x, t);
      if (k < 0) k = 0;
      if (k + 1 < s.x.length && s.x[k + 1] !== null && Math.abs(s.x[k + 1] - t) < Math.abs(s.x[k] - t)) ++k;
      return { series: s.title || s.y_col || '', column: s.y_col || null, t: s.x[k], value: s.y[k], unit: s.unit || '' };
    });
  }
  function showReadout(c, t) {
    c.cursor = t;
    c.values = readoutAt(c.panel, t);
    const shown = c.only ? c.values.filter(function (v, i) { return c.only(i); }) : c.values;
    const parts = shown.map(function (v) {
      // The drawn sample nearest the cursor; its own time when the decimated series has none at the cursor.
      const at = v.t !== null && Math.abs(v.t - t) > 1e-9 * Math.max(1, Math.abs(t)) ? ' (at ' + fmt(v.t, 7) + ' s)' : '';
      return v.series + ': ' + fmt(v.value, 6) + (v.unit && v.unit !== '-' ? ' ' + v.unit : '') + at;
    });
    c.readout.textContent = 't = ' + fmt(t, 6) + ' s  ·  ' + parts.join('  ·  ');
  }
  function onCursor(c) {
    const u = c.u;
    if (state.syncing || u.cursor.left === undefined || u.cursor.left === null || u.cursor.left < 0) return;
    const t = u.posToVal(u.cursor.left, 'x');
    if (!isFinite(t)) return;
    showReadout(c, t);
    if (!state.playing) setTime(t, c);
  }
  // One time span for every time plot shown: a zoom (drag, wheel), a pan (shift-drag or middle-drag) or a reset
  // (double-click) of one applies to all.
  function setSpan(min, max, from) {
    if (!(max > min) || state.spanning) return;
    state.spanning = true;
    try {
      for (const c of state.charts) if (c.time && c !== from) c.u.setScale('x', { min: min, max: max });
    } finally {
      state.spanning = false;
    }
  }
  function addPanZoom(c) {
    const u = c.u, over = u.over;
    over.addEventListener('wheel', function (e) {
      e.preventDefault();
      const x = u.posToVal(e.clientX - over.getBoundingClientRect().left, 'x');
      const min = u.scales.x.min, max = u.scales.x.max, f = e.deltaY < 0 ? 0.8 : 1.25;
      u.setScale('x', { min: x - (x - min) * f, max: x + (max - x) * f });
    }, { passive: false });
    u.root.addEventListener('mousedown', function (e) {
      if (!over.contains(e.target) || !(e.shiftKey || e.button === 1)) return;
      e.stopPropagation();
      e.preventDefault();
      const x0 = e.clientX, min = u.scales.x.min, max = u.scales.x.max, w = Math.max(over.clientWidth, 1);
      const move = function (ev) {
        const d = (ev.clientX - x0) / w * (max - min);
        u.setScale('x', { min: min - d, max: max - d });
      };
      const up = function () {
        document.removeEventListener('mousemove', move);
        document.removeEventListener('mouseup', up);
      };
      document.addEventListener('mousemove', move);
      document.addEventListener('mouseup', up);
    }, true);
  }
  function makeTimeChart(panel, box, emphasisOf) {
    const series = panel.series.filter(function (s) { return s.x.length > 0; });
    const p = { title: panel.title, series: series, unit: '' };
    const data = aligned(series);
    const axes = [{ label: panel.xlabel || 'time [s]' }, { label: panel.ylabel, size: 60 }];
    const scales = { x: { time: false } };
    if (series.some(function (s) { return s.y2; })) {
      axes.push({ label: panel.y2label, scale: 'y2', side: 1, grid: { show: false }, size: 60 });
      scales.y2 = { auto: true };
    }
    const c = { panel: p, readout: el('div', 'readout'), cursor: null, values: [], only: emphasisOf || null };
    const opts = {
      width: plotWidth(), height: 230, title: panel.title, scales: scales, axes: axes,
      series: [{ label: 'time' }].concat(series.map(function (s, i) {
        return seriesOpts(s, i, emphasisOf ? emphasisOf(i) : undefined);
      })),
      cursor: { drag: { x: true, y: false }, y: false },
      legend: { live: false, show: series.length <= 12 },
      hooks: {
        setCursor: [function () { onCursor(c); }],
        setScale: [function (u, key) { if (key === 'x' && c.u) setSpan(u.scales.x.min, u.scales.x.max, c); }],
      },
    };
    const wrap = el('div', 'panel');
    box.appendChild(wrap);
    c.u = new uPlot(opts, data, wrap);
    wrap.appendChild(c.readout);
    c.time = true;
    addPanZoom(c);
    return c;
  }
  // A polyline through the points in their order (uPlot's own linear paths assume x sorted; a hysteresis loop is not).
  function polyline(u, si) {
    const xs = u.data[si][0], ys = u.data[si][1], s = u.series[si];
    const p = new Path2D();
    let pen = false;
    for (let i = 0; i < xs.length; ++i) {
      const x = u.valToPos(xs[i], s.facets[0].scale, true), y = u.valToPos(ys[i], s.facets[1].scale, true);
      if (pen && !(s._breaks && s._breaks.has(i))) p.lineTo(x, y); else p.moveTo(x, y);
      pen = true;
    }
    return { stroke: p, fill: null, clip: null, band: null, gaps: null, flags: 0 };
  }
  // Dots at the points (samples and markers in the plane).
  function dots(u, si) {
    const xs = u.data[si][0], ys = u.data[si][1], s = u.series[si];
    const r = (s._dot || 2) * (window.devicePixelRatio || 1) / 2;
    const p = new Path2D();
    for (let i = 0; i < xs.length; ++i) {
      const x = u.valToPos(xs[i], s.facets[0].scale, true), y = u.valToPos(ys[i], s.facets[1].scale, true);
      p.moveTo(x + r, y);
      p.arc(x, y, r, 0, 2 * Math.PI);
    }
    return { stroke: null, fill: p, clip: null, band: null, gaps: null, flags: 0 };
  }
  function makeXYChart(panel, box, emphasisOf) {
    const series = panel.series.filter(function (s) { return s.x.length > 0; });
    // Points with a non-finite coordinate are left out; the curve is broken there (s._breaks: the points after one).
    const data = [null].concat(series.map(function (s) {
      const xs = [], ys = [];
      s._breaks = new Set();
      let gap = false;
      s.x.forEach(function (x, i) {
        if (x === null || s.y[i] === null) { gap = true; return; }
        if (gap && xs.length) s._breaks.add(xs.length);
        gap = false;
        xs.push(x);
        ys.push(s.y[i]);
      });
      return [xs, ys];
    }));
    const opts = {
      mode: 2, width: plotWidth(), height: 300, title: panel.title,
      scales: { x: { time: false, auto: true }, y: { auto: true } },
      axes: [{ label: panel.xlabel }, { label: panel.ylabel, size: 60 }],
      series: [{}].concat(series.map(function (s, i) {
        const o = seriesOpts(s, i, emphasisOf ? emphasisOf(s) : undefined);
        o._breaks = s._breaks;
        o.facets = [{ scale: 'x', auto: true }, { scale: 'y', auto: true }];
        delete o.scale;
        delete o.spanGaps;
        if (o.points.show) {  // a scatter: dots of the points' colour
          o.fill = o.points.fill;
          o._dot = o.points.size;
          o.paths = dots;
          o.points = { show: false };
        } else {
          o.paths = polyline;
        }
        return o;
      })),
      legend: { live: false, show: series.length <= 12 },
      cursor: { y: false },
    };
    const wrap = el('div', 'panel');
    box.appendChild(wrap);
    const u = new uPlot(opts, data, wrap);
    return { u: u, panel: { title: panel.title, series: series }, time: false, readout: null, values: [] };
  }
  function destroyCharts() {
    for (const c of state.charts) c.u.destroy();
    state.charts = [];
    document.getElementById('plots').replaceChildren();
  }
  function showFigure(k) {
    destroyCharts();
    const run = D.runs[state.run];
    const box = document.getElementById('plots');
    if (D.kind === 'sweep') {
      if (k === 1) buildFigureOverlay(box);
      else buildOverlay(box);
      state.figure = k;
      return;
    }
    const fig = (run.figures || [])[k];
    if (!fig) return;
    state.figure = k;
    for (const panel of fig.panels) {
      const c = panel.time_axis ? makeTimeChart(panel, box) : makeXYChart(panel, box);
      state.charts.push(c);
    }
    syncCursors();
  }
  function buildFigureSelect(run) {
    const sel = document.getElementById('figure-select');
    sel.replaceChildren();
    if (D.kind === 'sweep') {
      const a = el('option', null, D.key ? 'key signal of every run: ' + D.key.what : 'no key signal');
      a.value = '0';
      sel.appendChild(a);
      const f = sweepFigure();
      if (f) {
        const b = el('option', null, f.title + ' (every run)');
        b.value = '1';
        sel.appendChild(b);
      }
      sel.value = String(state.figure);
      return;
    }
    (run.figures || []).forEach(function (f, i) {
      const o = el('option', null, f.title);
      o.value = String(i);
      sel.appendChild(o);
    });
  }
  document.getElementById('figure-select').addEventListener('change', function (e) {
    showFigure(Number(e.target.value));
  });

  // ---------------------------------------------------------------------------------------------- sweeps
  function buildOverlay(box) {
    if (!D.key) return;
    const panel = { title: D.key.what + ' (selected run bold)', xlabel: D.key.xlabel, ylabel: D.key.ylabel,
                    series: [] };
    const runIdx = [];
    D.runs.forEach(function (r, i) {
      if (!r.key || !r.key.x.length) return;  // (the chart leaves out series without points)
      panel.series.push({ title: r.name, x: r.key.x, y: r.key.y, unit: D.key.unit || '' });
      runIdx.push(i);
    });
    if (!panel.series.length) return;
    const c = makeTimeChart(panel, box, function (i) { return runIdx[i] === state.run; });
    state.charts.push(c);
    syncCursors();
  }
  // The figure that characterises the sweep's type (curves in the plane: clamping curves, friction map), from the
  // first run that has it.
  function sweepFigure() {
    for (const r of D.runs) if (r.figures && r.figures.length) return r.figures[0];
    return null;
  }
  // That figure with every run's curves overlaid, the selected run's in red.
  function buildFigureOverlay(box) {
    const f = sweepFigure();
    if (!f) return;
    f.panels.forEach(function (p0, pi) {
      const panel = { title: p0.title + ' (selected run red)', xlabel: p0.xlabel, ylabel: p0.ylabel, series: [] };
      D.runs.forEach(function (r, ri) {
        const p = r.figures && r.figures[0] && r.figures[0].panels[pi];
        if (!p) return;
        for (const s of p.series) {
          const o = Object.assign({}, s);
          o.title = r.name + (s.title ? ' · ' + s.title : '');
          o.run = ri;
          panel.series.push(o);
        }
      });
      // Unselected runs first, so that the selected run is drawn on top.
      panel.series.sort(function (a, b) { return (a.run === state.run) - (b.run === state.run); });
      state.charts.push(makeXYChart(panel, box, function (s) { return s.run === state.run; }));
    });
  }
  function buildRunList() {
    if (D.kind !== 'sweep') return;
    document.getElementById('runs-box').hidden = false;
    const labelKeys = [];
    for (const r of D.runs) for (const kv of r.labels || []) if (labelKeys.indexOf(kv[0]) < 0) labelKeys.push(kv[0]);
    // The overrides that differ between the runs (those common to all say nothing about a run).
    const items = D.runs.map(function (r) { return String(r.overrides || '').split('; ').filter(Boolean); });
    const common = items.length ? items[0].filter(function (x) { return items.every(function (l) { return l.indexOf(x) >= 0; }); }) : [];
    const varies = items.map(function (l) { return l.filter(function (x) { return common.indexOf(x) < 0; }).join('; '); });
    const showVaries = labelKeys.length === 0 && varies.some(Boolean);
    const table = el('table'), head = el('tr');
    for (const h of ['run', 'status'].concat(labelKeys, showVaries ? ['set'] : [])) head.appendChild(el('th', null, h));
    table.appendChild(head);
    D.runs.forEach(function (r, i) {
      const tr = el('tr', 'run');
      tr.appendChild(el('td', null, r.name));
      tr.appendChild(el('td', null, r.status));
      const labels = new Map(r.labels || []);
      for (const k of labelKeys) tr.appendChild(el('td', null, labels.has(k) ? labels.get(k) : ''));
      if (showVaries) tr.appendChild(el('td', null, varies[i]));
      tr.addEventListener('click', function () { selectRun(i); });
      table.appendChild(tr);
    });
    document.getElementById('runs').appendChild(table);
  }

  // ------------------------------------------------------------------------------------------------ time
  const slider = document.getElementById('slider');
  function timeRange(run) {
    const m = run.motion;
    if (m && m.t.length) return [m.t[0], m.t[m.t.length - 1]];
    let lo = Infinity, hi = -Infinity;
    for (const f of run.figures || [])
      for (const p of f.panels)
        if (p.time_axis) for (const s of p.series) for (const x of s.x) if (x !== null) { lo = Math.min(lo, x); hi = Math.max(hi, x); }
    if (run.key) for (const x of run.key.x) if (x !== null) { lo = Math.min(lo, x); hi = Math.max(hi, x); }
    return isFinite(lo) ? [lo, hi] : [0, 0];
  }
  // Every time plot's cursor (but that of `from`, the plot the mouse moves over) to the current time.
  function syncCursors(from) {
    state.syncing = true;
    try {
      for (const c of state.charts) {
        if (!c.time || c === from) continue;
        c.u.setCursor({ left: c.u.valToPos(state.t, 'x'), top: c.u.cursor.top > 0 ? c.u.cursor.top : 20 }, false);
        showReadout(c, state.t);
      }
    } finally {
      state.syncing = false;
    }
  }
  function setTime(t, from) {
    const run = D.runs[state.run];
    if (!isFinite(t)) return;
    t = Math.min(state.t1, Math.max(state.t0, t));
    state.t = t;
    const q = anglesAt(run, t);
    poseArm(q);
    showGauges(q);
    slider.value = String(state.t1 > state.t0 ? Math.round(1e6 * (t - state.t0) / (state.t1 - state.t0)) : 0);
    document.getElementById('time-label').textContent =
        't = ' + t.toFixed(4) + ' s / ' + state.t1.toFixed(3) + ' s';
    syncCursors(from);
  }
  slider.addEventListener('input', function () {
    setTime(state.t0 + (state.t1 - state.t0) * Number(slider.value) / 1e6);
  });
  const speed = document.getElementById('speed');
  for (const s of [0.05, 0.1, 0.25, 0.5, 1, 2, 5, 10]) {
    const o = el('option', null, s + '×');
    o.value = String(s);
    if (s === 1) o.selected = true;
    speed.appendChild(o);
  }
  speed.addEventListener('change', function () { state.speed = Number(speed.value); });
  const play = document.getElementById('play');
  function setPlaying(on) {
    state.playing = on;
    play.textContent = on ? '❚❚' : '▶';
    state.last = performance.now();
    if (on) requestAnimationFrame(tick);
  }
  play.addEventListener('click', function () { setPlaying(!state.playing); });
  document.addEventListener('keydown', function (e) {
    if (e.code === 'Space' && e.target === document.body) { e.preventDefault(); setPlaying(!state.playing); }
  });
  function tick(now) {
    if (!state.playing) return;
    const dt = Math.min(0.1, (now - state.last) / 1000);
    state.last = now;
    let t = state.t + dt * state.speed;
    if (t > state.t1) t = state.t0;
    setTime(t);
    requestAnimationFrame(tick);
  }

  function selectRun(i) {
    if (i < 0 || i >= D.runs.length) throw new Error('no run ' + i);
    state.run = i;
    const run = D.runs[i];
    document.querySelectorAll('#runs tr.run').forEach(function (tr, k) { tr.classList.toggle('selected', k === i); });
    showNotes(run);
    showSummary(run);
    showRunGeometry(run);
    buildGauges(run);
    const range = timeRange(run);
    state.t0 = range[0];
    state.t1 = range[1];
    if (D.kind !== 'sweep') state.figure = run.first_figure || 0;
    buildFigureSelect(run);
    showFigure(state.figure);
    document.getElementById('figure-select').value = String(state.figure);
    setTime(Math.min(Math.max(state.t, state.t0), state.t1));
  }

  // --------------------------------------------------------------------------------------------- the interface
  api.setTime = function (t) { setPlaying(false); setTime(Number(t)); return state.t; };
  api.time = function () { return state.t; };
  api.selectRun = function (i) { selectRun(i); };
  api.selectFigure = function (k) { showFigure(k); document.getElementById('figure-select').value = String(k); };
  api.play = function (on) { setPlaying(on !== false); };
  // World position of the drawn tool centre point [m], null without an arm.
  api.tcpPosition = function () {
    if (!arm.ok) return null;
    arm.scene.updateMatrixWorld(true);
    const p = arm.tcp.getWorldPosition(new THREE.Vector3());
    return [p.x, p.y, p.z];
  };
  // Joint angles drawn now [rad or m].
  api.angles = function () { return anglesAt(D.runs[state.run], state.t); };
  // The charts now shown: title, whether it is a time panel, its series titles and columns.
  api.panels = function () {
    return state.charts.map(function (c) {
      return { title: c.panel.title, time: c.time, figure: D.kind === 'sweep' ? null : state.figure,
               series: c.panel.series.map(function (s) { return { title: s.title, column: s.y_col || null }; }) };
    });
  };
  // The cursor readout of chart k: per series the drawn sample nearest the cursor (time, value, unit).
  api.readout = function (k) {
    const c = state.charts[k];
    if (!c || !c.time) return null;
    return { cursor: c.cursor, text: c.readout.textContent, values: c.values };
  };
  api.webgl = function () { return !!arm.renderer; };
  // Per URDF visual drawn: its link and the centre of its bounding box in the base frame [m] (null when not drawn).
  api.visuals = function () {
    if (!arm.ok) return [];
    arm.scene.updateMatrixWorld(true);
    return arm.visuals.map(function (v) {
      if (!v.shape) return { link: v.link, center: null };
      const c = new THREE.Box3().setFromObject(v.shape).getCenter(new THREE.Vector3());
      return { link: v.link, center: [c.x, c.y, c.z] };
    });
  };
  // The time span [s] plot k shows.
  api.span = function (k) {
    const c = state.charts[k];
    return c && c.time ? [c.u.scales.x.min, c.u.scales.x.max] : null;
  };

  try {
    buildArm();
    buildRunList();
    selectRun(0);
    window.addEventListener('resize', function () {
      for (const c of state.charts) c.u.setSize({ width: plotWidth(), height: c.u.height });
    });
    api.ready = true;
  } catch (e) {
    report('viewer: ' + (e && e.stack ? e.stack : e));
  }
})();
