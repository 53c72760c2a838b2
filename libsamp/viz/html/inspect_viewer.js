// samp inspect viewer: the shape manifold phi(z) = mu + W z with a slider per
// eigen-shape (in units of its sigma). The zero level set is extracted in the
// page with three.js' MarchingCubes on the model grid (padded into a cube).
(function () {
  'use strict';
  var C = window.sampCommon;
  var data = JSON.parse(document.getElementById('samp-data').textContent);
  var BACKGROUND = [244, 245, 247];

  var app = C.element('div', { id: 'samp-app' }, document.body);
  var bar = C.element('div', { id: 'samp-bar' }, app);
  C.element('h1', {}, bar, data.title);
  var resetButton = C.element('button', { id: 'samp-reset' }, bar, 'mean shape');
  var info = C.element('span', { id: 'samp-info' }, bar, '');
  var main = C.element('div', { id: 'samp-main' }, app);
  var view = C.element('div', { id: 'samp-view' }, main);
  var panel = C.element('aside', { id: 'samp-panel' }, main);

  var three = C.threeView(view, BACKGROUND, { fov: 35, near: 0.05, far: 200, hemisphere: 0.7, sun: 0.6,
                                              sunAt: [-3, 6, 4] });
  var renderer = three.renderer, scene = three.scene, camera = three.camera, controls = three.controls;
  var render = three.render, resize = three.resize;
  var object = C.kittiGroup();  // object frame (x front, y down, z left) -> three.js
  scene.add(object);
  object.add(new THREE.AxesHelper(0.8));

  // ---- The manifold ---------------------------------------------------------------------------
  var dims = data.grid.dims, voxel = data.grid.voxel_size, origin = data.grid.origin;
  var mean = C.typed(data.mean, Float32Array);
  var components = data.components.map(function (c) { return C.typed(c, Float32Array); });
  var sigmas = data.sigmas;
  var code = sigmas.map(function () { return 0; });  // in sigmas
  var size = Math.max(dims[0], dims[1], dims[2]) + 3;  // one outside layer on each side, MarchingCubes skips its border
  var cubes = new THREE.MarchingCubes(size, new THREE.MeshLambertMaterial(), false, false);
  cubes.isolation = 0;
  var material = new THREE.MeshLambertMaterial({ color: 0x6f9fd8, side: THREE.DoubleSide });
  var shape = new THREE.Mesh(new THREE.BufferGeometry(), material);
  shape.name = 'shape';
  // MarchingCubes places cell index i at (i - size/2) / (size/2); grid sample
  // (i, j, k) is padded cell (i + 1, j + 1, k + 1) at origin + voxel (i, j, k).
  var half = size / 2;
  shape.scale.setScalar(voxel * half);
  shape.position.set(origin[0] + voxel * (half - 1), origin[1] + voxel * (half - 1), origin[2] + voxel * (half - 1));
  object.add(shape);
  var numTriangles = 0;

  function rebuild() {
    cubes.reset();
    var field = cubes.field, outside = -3 * voxel;
    for (var q = 0; q < field.length; q++) field[q] = outside;
    var nx = dims[0], ny = dims[1], nz = dims[2];
    var weights = code.map(function (k, i) { return k * sigmas[i]; });
    for (var k = 0; k < nz; k++) {
      for (var j = 0; j < ny; j++) {
        for (var i = 0; i < nx; i++) {
          var v = i + nx * (j + ny * k);
          var phi = mean[v];
          for (var c = 0; c < weights.length; c++) if (weights[c] !== 0) phi += weights[c] * components[c][v];
          field[(i + 1) + size * ((j + 1) + size * (k + 1))] = -phi;  // MarchingCubes: inside is above the isolation
        }
      }
    }
    var geometry = cubes.generateBufferGeometry();
    shape.geometry.dispose();
    shape.geometry = geometry;
    numTriangles = geometry.attributes.position ? geometry.attributes.position.count / 3 : 0;
    geometry.computeBoundingBox();
    var b = geometry.boundingBox;
    var extent = numTriangles ? b.getSize(new THREE.Vector3()).multiplyScalar(voxel * half) : new THREE.Vector3();
    info.textContent = numTriangles + ' triangles; l×h×w ' + extent.x.toFixed(2) + '×' + extent.y.toFixed(2) + '×' +
                       extent.z.toFixed(2) + ' m; z/σ = (' + code.map(function (v) { return v.toFixed(1); }).join(', ') + ')';
    render();
  }

  // ---- Sliders -------------------------------------------------------------------------------------
  C.element('h2', {}, panel, 'Eigen-shapes (' + sigmas.length + ' components, ' + data.num_training_shapes + ' training shapes)');
  C.element('div', { class: 'samp-note' }, panel, 'Each slider sets z_i in units of σ_i = sqrt(eigenvalue); the surface is ' +
            'the zero level set of μ + Σ z_i w_i on the model grid (' + dims.join('×') + ' voxels of ' + voxel + ' m).');
  var sliders = sigmas.map(function (sigma, i) {
    var row = C.element('div', { class: 'samp-slider' }, panel);
    C.element('span', {}, row, 'z' + (i + 1));
    var s = C.element('input', { id: 'samp-z' + (i + 1), type: 'range', min: -data.slider_sigmas, max: data.slider_sigmas,
                                 step: 0.1, value: 0 }, row);
    var value = C.element('span', {}, row, '0.0σ');
    C.element('div', { class: 'samp-note' }, panel, 'σ = ' + sigma.toFixed(3) + ', explains ' +
              (100 * data.explained[i]).toFixed(1) + ' % of the variance');
    s.addEventListener('input', function () {
      code[i] = Number(s.value);
      value.textContent = code[i].toFixed(1) + 'σ';
      rebuild();
    });
    return s;
  });
  resetButton.addEventListener('click', function () {
    sliders.forEach(function (s, i) { s.value = 0; code[i] = 0; s.dispatchEvent(new Event('input')); });
  });

  controls.addEventListener('change', render);
  window.addEventListener('resize', resize);
  // A three-quarter view from the front left, above.
  camera.position.set(5.5, 3.0, -4.5);  // three.js frame: object x front -> x, z left -> -z
  controls.target.set(0, 0.7, 0);
  controls.update();
  rebuild();
  resize();
  var loadMs = performance.now();

  window.sampViewer = { scene: scene, render: render, numTriangles: function () { return numTriangles; } };
  // #z=2,0,-1 opens with that code (in sigmas).
  var zMatch = /z=([-0-9.,]+)/.exec(window.location.hash);
  if (zMatch) {
    zMatch[1].split(',').forEach(function (v, i) {
      if (i < sliders.length && v !== '') { sliders[i].value = Number(v); sliders[i].dispatchEvent(new Event('input')); }
    });
  }
  if (/selftest/.test(window.location.hash)) {
    var result = { kind: 'inspect', load_ms: loadMs, three_revision: THREE.REVISION, components: sigmas.length };
    result.mean_triangles = numTriangles;
    result.nonblank_share = C.nonBlankShare(renderer, BACKGROUND);
    var before = shape.geometry.boundingBox.clone();
    if (sliders.length) {
      sliders[0].value = 2;
      sliders[0].dispatchEvent(new Event('input'));
      var after = shape.geometry.boundingBox;
      result.slider_triangles = numTriangles;
      result.slider_box_change = after.min.distanceTo(before.min) + after.max.distanceTo(before.max);
    }
    C.writeSelfTest(result);
  }
})();
