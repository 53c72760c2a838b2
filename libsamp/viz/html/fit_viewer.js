// samp fit viewer: the tracks of a `samp fit` run over the frames of a sequence.
// Data: the JSON of <script id="samp-data"> (libsamp/viz/html_viewer.cc).
// Coordinates stay those of the fit (world = the ego-pose frame, KITTI axes)
// inside a group that turns them into three.js' y-up frame.
(function () {
  'use strict';
  var C = window.sampCommon;
  var marks = { script_start_ms: performance.now() };  // after the page and three.js are parsed
  var data = JSON.parse(document.getElementById('samp-data').textContent);
  marks.json_parsed_ms = performance.now();
  var BACKGROUND = [244, 245, 247];
  var ERROR_ABOVE = new THREE.Color(200 / 255, 30 / 255, 30 / 255);

  // ---- Layout -------------------------------------------------------------------
  var app = C.element('div', { id: 'samp-app' }, document.body);
  var bar = C.element('div', { id: 'samp-bar' }, app);
  C.element('h1', {}, bar, data.title);
  var sequenceSelect = C.element('select', { id: 'samp-sequence' }, bar);
  var playButton = C.element('button', { id: 'samp-play' }, bar, 'play');
  var slider = C.element('input', { id: 'samp-frame', type: 'range', min: 0, max: 0, value: 0, step: 1 }, bar);
  var frameLabel = C.element('span', { id: 'samp-frame-label' }, bar, '');
  function checkbox(id, text, checked) {
    var label = C.element('label', {}, bar);
    var box = C.element('input', { id: id, type: 'checkbox' }, label);
    box.checked = checked;
    label.appendChild(document.createTextNode(' ' + text));
    return box;
  }
  var allFramesBox = checkbox('samp-all-frames', 'points of all frames', false);
  var detectionsBox = checkbox('samp-detections', 'detections', true);
  var errorBox = checkbox('samp-errors', 'error colouring', false);
  var truthBox = checkbox('samp-truth', 'true boxes', true);
  var main = C.element('div', { id: 'samp-main' }, app);
  var view = C.element('div', { id: 'samp-view' }, main);
  var panel = C.element('aside', { id: 'samp-panel' }, main);
  var legend = C.element('div', { class: 'samp-legend' }, view);

  // ---- three.js set-up ------------------------------------------------------------
  var three = C.threeView(view, BACKGROUND, { fov: 45, near: 0.1, far: 2000, hemisphere: 0.75, sun: 0.55,
                                              sunAt: [-20, 40, 15] });
  var renderer = three.renderer, scene = three.scene, camera = three.camera, controls = three.controls;
  var render = three.render, resize = three.resize;
  controls.enableDamping = false;
  var world = C.kittiGroup();  // KITTI world -> three.js
  scene.add(world);

  function pose(array, k) {  // x y z qx qy qz qw of pose k
    var o = 7 * k;
    return { p: new THREE.Vector3(array[o], array[o + 1], array[o + 2]),
             q: new THREE.Quaternion(array[o + 3], array[o + 4], array[o + 5], array[o + 6]) };
  }
  function place(object, pq) {
    object.position.copy(pq.p);
    object.quaternion.copy(pq.q);
  }
  // A wireframe box of size l h w (object x y z) standing on the object origin (y down).
  function boxEdges(size, color) {
    var geometry = new THREE.BoxBufferGeometry(size[0], size[1], size[2]);
    geometry.translate(0, -size[1] / 2, 0);
    var lines = new THREE.LineSegments(new THREE.EdgesGeometry(geometry),
                                       new THREE.LineBasicMaterial({ color: color }));
    return lines;
  }
  function errorColor(e, tau, color) {
    if (e > tau) return color.copy(ERROR_ABOVE);
    // viridis, 5 stops
    var stops = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
    var t = Math.max(0, e / tau) * (stops.length - 1), i = Math.min(stops.length - 2, Math.floor(t)), f = t - i;
    return color.setRGB((stops[i][0] + (stops[i + 1][0] - stops[i][0]) * f) / 255,
                        (stops[i][1] + (stops[i + 1][1] - stops[i][1]) * f) / 255,
                        (stops[i][2] + (stops[i + 1][2] - stops[i][2]) * f) / 255);
  }

  // ---- Scene of each sequence -----------------------------------------------------------
  var sequences = data.sequences.map(function (s, si) {
    var group = new THREE.Group();
    group.visible = false;
    world.add(group);
    var ego = C.typed(s.ego, Float32Array);
    var seq = { data: s, group: group, tracks: [], truth: [], frameIndex: {}, hasErrors: false };
    s.frames.forEach(function (f, i) { seq.frameIndex[f] = i; });
    var lo = new THREE.Vector3(Infinity, Infinity, Infinity), hi = new THREE.Vector3(-Infinity, -Infinity, -Infinity);
    s.tracks.forEach(function (t) {
      var color = new THREE.Color(t.color[0] / 255, t.color[1] / 255, t.color[2] / 255);
      var poses = C.typed(t.poses, Float32Array);
      var detections = C.typed(t.detections, Float32Array);
      var track = { data: t, color: color, poses: poses, index: {}, mesh: null, points: null, detection: null };
      t.frames.forEach(function (f, k) { track.index[f] = k; });
      // Mesh (object frame).
      if (t.mesh) {
        var geometry = new THREE.BufferGeometry();
        geometry.setAttribute('position', new THREE.BufferAttribute(C.typed(t.mesh.positions, Float32Array), 3));
        geometry.setIndex(new THREE.BufferAttribute(C.typed(t.mesh.indices, Uint32Array), 1));
        geometry.computeVertexNormals();
        var n = t.mesh.num_vertices;
        var colors = new Float32Array(3 * n);
        geometry.setAttribute('color', new THREE.BufferAttribute(colors, 3));
        if (t.mesh.errors) {
          track.errors = C.typed(t.mesh.errors, Float32Array);
          seq.hasErrors = true;
        }
        var material = new THREE.MeshLambertMaterial({ color: 0xffffff, vertexColors: THREE.VertexColors,
                                                       side: THREE.DoubleSide, transparent: true, opacity: 0.9 });
        track.mesh = new THREE.Mesh(geometry, material);
        track.mesh.name = 'mesh track ' + t.id;
        group.add(track.mesh);
      }
      // Points of all frames in the world, one buffer; the draw range picks a frame.
      var raw = C.typed(t.points.data, Int16Array);
      var positions = new Float32Array(raw.length);
      var offsets = t.points.offsets, scales = t.points.scales;
      for (var k = 0; k < t.frames.length; k++) {
        var origin = pose(poses, k).p, s0 = scales[k];
        for (var i = offsets[k]; i < offsets[k + 1]; i++) {
          positions[3 * i] = origin.x + raw[3 * i] * s0;
          positions[3 * i + 1] = origin.y + raw[3 * i + 1] * s0;
          positions[3 * i + 2] = origin.z + raw[3 * i + 2] * s0;
        }
        lo.min(origin); hi.max(origin);
      }
      var pointGeometry = new THREE.BufferGeometry();
      pointGeometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
      track.points = new THREE.Points(pointGeometry, new THREE.PointsMaterial({ color: color, size: 0.07 }));
      track.points.name = 'points track ' + t.id;
      track.points.frustumCulled = false;
      group.add(track.points);
      // Trajectory (lifted 5 cm so it is not hidden by the road).
      var path = [];
      for (var k2 = 0; k2 < t.frames.length; k2++) {
        var p = pose(poses, k2).p;
        path.push(new THREE.Vector3(p.x, p.y - 0.05, p.z));
      }
      var line = new THREE.Line(new THREE.BufferGeometry().setFromPoints(path),
                                new THREE.LineBasicMaterial({ color: color }));
      group.add(line);
      // Detection box of the current frame.
      track.detectionData = detections;
      track.detection = boxEdges([1, 1, 1], 0xe63c28);
      track.detection.visible = false;
      group.add(track.detection);
      seq.tracks.push(track);
    });
    s.ground_truth.forEach(function (g) {
      var box = boxEdges(g.size, 0x505050);
      box.visible = false;
      group.add(box);
      var truth = { data: g, box: box, poses: C.typed(g.poses, Float32Array), index: {} };
      g.frames.forEach(function (f, k) { truth.index[f] = k; });
      seq.truth.push(truth);
    });
    for (var e = 0; e < s.frames.length; e++) { lo.min(pose(ego, e).p); hi.max(pose(ego, e).p); }
    if (!isFinite(lo.x)) { lo.set(-10, 0, 0); hi.set(10, 0, 40); }
    seq.lo = lo; seq.hi = hi;
    // Road plane n . x + d = 0 (n up), a rectangle around the scene with a grid.
    var n = new THREE.Vector3(s.ground_plane[0], s.ground_plane[1], s.ground_plane[2]).normalize();
    var centre = lo.clone().add(hi).multiplyScalar(0.5);
    var size = Math.max(hi.x - lo.x, hi.z - lo.z) + 30;
    var onPlane = centre.clone().sub(n.clone().multiplyScalar(n.dot(centre) + s.ground_plane[3]));
    var road = new THREE.Mesh(new THREE.PlaneBufferGeometry(size, size),
                              new THREE.MeshBasicMaterial({ color: 0xc9ccd1, side: THREE.DoubleSide, transparent: true,
                                                            opacity: 0.45, depthWrite: false }));
    road.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), n);
    road.position.copy(onPlane);
    road.name = 'road plane';
    group.add(road);
    var grid = new THREE.GridHelper(size, Math.round(size / 5), 0xa0a4aa, 0xb8bcc2);
    grid.quaternion.setFromUnitVectors(new THREE.Vector3(0, 1, 0), n);
    grid.position.copy(onPlane);
    group.add(grid);
    // The ego camera of the current frame: a small pyramid.
    var cone = new THREE.Mesh(new THREE.ConeBufferGeometry(0.6, 1.4, 4),
                              new THREE.MeshLambertMaterial({ color: 0x404040 }));
    cone.geometry.rotateX(Math.PI / 2);  // apex along +z (forward)
    seq.egoMarker = cone;
    seq.ego = ego;
    group.add(cone);
    var option = C.element('option', { value: si }, sequenceSelect, s.name);
    return seq;
  });
  if (sequences.length < 2) sequenceSelect.style.display = 'none';
  marks.scene_built_ms = performance.now();

  // ---- State ----------------------------------------------------------------------------------
  var current = null, frame = 0, playing = null, selected = null;

  function updateColors(seq) {
    var byError = errorBox.checked && seq.hasErrors;
    var tmp = new THREE.Color();
    seq.tracks.forEach(function (track) {
      if (!track.mesh) return;
      var colors = track.mesh.geometry.attributes.color;
      for (var i = 0; i < colors.count; i++) {
        if (byError && track.errors) errorColor(track.errors[i], seq.data.error_tau, tmp);
        else if (byError) tmp.setRGB(0.75, 0.75, 0.75);
        else tmp.copy(track.color).lerp(new THREE.Color(1, 1, 1), 0.25);
        colors.setXYZ(i, tmp.r, tmp.g, tmp.b);
      }
      colors.needsUpdate = true;
    });
    legend.innerHTML = '';
    if (byError) {
      C.element('div', {}, legend, 'distance to the true surface');
      var canvas = C.element('canvas', { class: 'samp-colorbar', width: 160, height: 10 }, legend);
      var ctx = canvas.getContext('2d');
      for (var x = 0; x < 160; x++) {
        errorColor(x / 159 * seq.data.error_tau * 1.0, seq.data.error_tau, tmp);
        ctx.fillStyle = '#' + tmp.getHexString();
        ctx.fillRect(x, 0, 1, 10);
      }
      C.element('div', {}, legend, '0 … τ = ' + seq.data.error_tau + ' m; red: above τ');
    } else {
      C.element('div', {}, legend, 'points: this frame\'s stereo points of each track; mesh: fitted shape at the fitted pose; ' +
                'red boxes: detections' + (seq.truth.length ? '; grey boxes: ground truth' : '') +
                '; road: ' + seq.data.ground_plane_source);
    }
  }

  function setFrame(i) {
    var s = current.data;
    frame = Math.max(0, Math.min(s.frames.length - 1, i | 0));
    slider.value = frame;
    var f = s.frames[frame];
    frameLabel.textContent = 'frame ' + f + ' (' + (frame + 1) + '/' + s.frames.length + ')';
    current.tracks.forEach(function (track) {
      var k = track.index[f];
      var present = k !== undefined;
      if (track.mesh) {
        track.mesh.visible = present;
        if (present) place(track.mesh, pose(track.poses, k));
      }
      var offsets = track.data.points.offsets;
      if (allFramesBox.checked) {
        track.points.visible = true;
        track.points.geometry.setDrawRange(0, offsets[offsets.length - 1]);
      } else {
        track.points.visible = present;
        if (present) track.points.geometry.setDrawRange(offsets[k], offsets[k + 1] - offsets[k]);
      }
      var d = track.detectionData;
      var has = present && !isNaN(d[10 * k]);
      track.detection.visible = has && detectionsBox.checked;
      if (has) {
        track.detection.position.set(d[10 * k], d[10 * k + 1], d[10 * k + 2]);
        track.detection.quaternion.set(d[10 * k + 3], d[10 * k + 4], d[10 * k + 5], d[10 * k + 6]);
        track.detection.scale.set(d[10 * k + 7], d[10 * k + 8], d[10 * k + 9]);
      }
    });
    current.truth.forEach(function (truth) {
      var k = truth.index[f];
      truth.box.visible = k !== undefined && truthBox.checked;
      if (k !== undefined) {
        var o = 7 * k, p = truth.poses;
        truth.box.position.set(p[o], p[o + 1], p[o + 2]);
        truth.box.quaternion.set(p[o + 3], p[o + 4], p[o + 5], p[o + 6]);
      }
    });
    place(current.egoMarker, pose(current.ego, frame));
    render();
  }

  // Converts a KITTI world point to three.js coordinates.
  function toScene(v) { return new THREE.Vector3(v.x, -v.y, -v.z); }

  function viewAll() {
    var lo = current.lo, hi = current.hi;
    var centre = lo.clone().add(hi).multiplyScalar(0.5);
    var span = Math.max(10, hi.x - lo.x, hi.z - lo.z);
    // From behind and above the first camera, looking at the scene's centre.
    var eye = new THREE.Vector3(centre.x, centre.y - 0.4 * span, lo.z - 0.2 * span);
    controls.target.copy(toScene(centre));
    camera.position.copy(toScene(eye));
    controls.update();
  }

  function focusTrack(track) {
    selected = track;
    Array.prototype.forEach.call(panel.querySelectorAll('tr.samp-track'), function (row) {
      row.classList.toggle('selected', Number(row.dataset.track) === track.data.id);
    });
    var k = track.index[current.data.frames[frame]];
    if (k === undefined) k = 0;
    var p = pose(track.poses, k).p;
    var target = toScene(p);
    var offset = camera.position.clone().sub(controls.target).setLength(12);
    controls.target.copy(target);
    camera.position.copy(target.clone().add(offset));
    controls.update();
    render();
  }

  function summaryOf(t) {
    var points = t.num_points.reduce(function (a, b) { return a + b; }, 0);
    var speed = t.speed.reduce(function (a, b) { return a + b; }, 0) / Math.max(1, t.speed.length);
    var models = {};
    t.motion_model.forEach(function (m) { if (m !== 'none') models[m] = (models[m] || 0) + 1; });
    var size = t.box_min ? [t.box_max[0] - t.box_min[0], t.box_max[1] - t.box_min[1], t.box_max[2] - t.box_min[2]] : null;
    return { points: points, speed: speed,
             models: Object.keys(models).map(function (m) { return m + ' ' + models[m]; }).join(', '),
             size: size ? size.map(function (v) { return v.toFixed(2); }).join('×') : '–' };
  }

  function buildPanel(seq) {
    panel.innerHTML = '';
    C.element('h2', {}, panel, seq.data.name + ': ' + seq.tracks.length + ' tracks, ' + seq.data.frames.length + ' frames');
    C.element('div', { class: 'samp-note' }, panel, 'model ' + data.model + '. Click a track to focus it; drag to orbit, ' +
              'wheel to zoom, right-drag to pan.');
    var table = C.element('table', { id: 'samp-tracks' }, panel);
    var head = C.element('tr', {}, table);
    ['track', 'frames', 'points', 'cost', 'speed', 'motion', 'l×h×w m'].forEach(function (h) { C.element('th', {}, head, h); });
    seq.tracks.forEach(function (track) {
      var t = track.data, s = summaryOf(t);
      var row = C.element('tr', { class: 'samp-track', 'data-track': t.id }, table);
      var cell = C.element('td', {}, row);
      var swatch = C.element('span', { class: 'samp-swatch' }, cell);
      swatch.style.background = '#' + track.color.getHexString();
      cell.appendChild(document.createTextNode(String(t.id)));
      C.element('td', {}, row, String(t.frames.length));
      C.element('td', {}, row, String(s.points));
      C.element('td', {}, row, C.fixed(t.initial_cost, 3) + '→' + C.fixed(t.final_cost, 3));
      C.element('td', {}, row, C.fixed(s.speed, 1) + ' m/s');
      C.element('td', {}, row, s.models);
      C.element('td', {}, row, s.size);
      row.addEventListener('click', function () { focusTrack(track); });
    });
    if (seq.hasErrors) {
      C.element('div', { class: 'samp-note' }, panel, 'Ground truth found: "error colouring" shows each surface\'s ' +
                'distance to its true car at τ = ' + seq.data.error_tau + ' m.');
    }
  }

  function selectSequence(index) {
    sequences.forEach(function (s, i) { s.group.visible = i === index; });
    current = sequences[index];
    slider.max = Math.max(0, current.data.frames.length - 1);
    errorBox.disabled = !current.hasErrors;
    errorBox.checked = current.hasErrors && errorBox.checked;
    truthBox.disabled = current.truth.length === 0;
    buildPanel(current);
    updateColors(current);
    viewAll();
    setFrame(0);
  }


  function togglePlay() {
    if (playing) {
      clearInterval(playing);
      playing = null;
      playButton.textContent = 'play';
      return;
    }
    playButton.textContent = 'pause';
    playing = setInterval(function () { setFrame((frame + 1) % current.data.frames.length); }, 100);
  }

  slider.addEventListener('input', function () { setFrame(Number(slider.value)); });
  playButton.addEventListener('click', togglePlay);
  sequenceSelect.addEventListener('change', function () { selectSequence(Number(sequenceSelect.value)); });
  [allFramesBox, detectionsBox, truthBox].forEach(function (b) { b.addEventListener('change', function () { setFrame(frame); }); });
  errorBox.addEventListener('change', function () { updateColors(current); render(); });
  controls.addEventListener('change', render);
  window.addEventListener('resize', resize);

  if (sequences.length === 0) {
    C.element('h2', {}, panel, 'No fitted sequence in this run.');
  } else {
    selectSequence(0);
  }
  resize();
  var loadMs = performance.now();

  // ---- The page's interface for tests ------------------------------------------------------------
  function meshPositions() {
    return current.tracks.filter(function (t) { return t.mesh && t.mesh.visible; }).map(function (t) {
      return [t.mesh.position.x, t.mesh.position.y, t.mesh.position.z];
    });
  }
  window.sampViewer = {
    scene: scene, setFrame: setFrame, render: render,
    numFrames: function () { return current ? current.data.frames.length : 0; },
    counts: function () {
      var meshes = 0, pointSets = 0, visibleMeshes = 0, visiblePointSets = 0;
      if (current) current.tracks.forEach(function (t) {
        if (t.mesh) { meshes++; if (t.mesh.visible) visibleMeshes++; }
        pointSets++; if (t.points.visible) visiblePointSets++;
      });
      return { meshes: meshes, point_sets: pointSets, visible_meshes: visibleMeshes, visible_point_sets: visiblePointSets };
    }
  };
  var hash = window.location.hash;
  var frameMatch = /frame=(\d+)/.exec(hash);
  if (frameMatch && current) setFrame(Number(frameMatch[1]));
  if (/errors/.test(hash) && current && current.hasErrors) { errorBox.checked = true; updateColors(current); render(); }
  if (/selftest/.test(hash)) {
    var result = { kind: 'fit', load_ms: loadMs, marks: marks, three_revision: THREE.REVISION, sequences: sequences.length };
    if (current) {
      setFrame(0);
      result.frame0 = window.sampViewer.counts();
      result.nonblank_share = C.nonBlankShare(renderer, BACKGROUND);
      var first = meshPositions();
      var firstPoints = current.tracks.map(function (t) { return t.points.geometry.drawRange.start; });
      // Move the slider as a user would: its input event sets the frame.
      slider.value = current.data.frames.length - 1;
      slider.dispatchEvent(new Event('input'));
      result.slider_frame = frame;
      result.last = window.sampViewer.counts();
      var last = meshPositions();
      var lastPoints = current.tracks.map(function (t) { return t.points.geometry.drawRange.start; });
      var moved = 0;
      for (var i = 0; i < Math.min(first.length, last.length); i++) {
        var dx = first[i][0] - last[i][0], dy = first[i][1] - last[i][1], dz = first[i][2] - last[i][2];
        moved = Math.max(moved, Math.sqrt(dx * dx + dy * dy + dz * dz));
      }
      result.max_mesh_displacement = moved;
      result.point_ranges_changed = firstPoints.some(function (s, i) { return s !== lastPoints[i]; });
      result.num_frames = current.data.frames.length;
      setFrame(Math.floor((current.data.frames.length - 1) / 2));
    }
    C.writeSelfTest(result);
  }
})();
