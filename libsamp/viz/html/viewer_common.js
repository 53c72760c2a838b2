// samp viewers: helpers shared by the fit and the inspect page (window.sampCommon).
(function () {
  'use strict';
  function bytes(base64) {
    var text = atob(base64);
    var out = new Uint8Array(text.length);
    for (var i = 0; i < text.length; i++) out[i] = text.charCodeAt(i);
    return out;
  }
  function typed(base64, Type) {
    var b = bytes(base64);
    return new Type(b.buffer, b.byteOffset, b.byteLength / Type.BYTES_PER_ELEMENT);
  }
  function element(tag, attributes, parent, text) {
    var e = document.createElement(tag);
    for (var k in attributes || {}) e.setAttribute(k, attributes[k]);
    if (text !== undefined) e.textContent = text;
    if (parent) parent.appendChild(e);
    return e;
  }
  // KITTI-like frames (x right, y down, z forward) into three.js (y up): a
  // rotation by pi about x, (x, y, z) -> (x, -y, -z).
  function kittiGroup() {
    var g = new THREE.Group();
    g.rotation.x = Math.PI;
    return g;
  }
  function fixed(v, digits) { return (v === undefined || v === null || isNaN(v)) ? '–' : Number(v).toFixed(digits); }
  // Share of pixels that differ from the background colour (0..1), from the
  // drawing buffer (the renderer keeps it: preserveDrawingBuffer).
  function nonBlankShare(renderer, background) {
    var gl = renderer.getContext();
    var w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    var px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    var differ = 0;
    for (var i = 0; i < px.length; i += 4) {
      if (Math.abs(px[i] - background[0]) + Math.abs(px[i + 1] - background[1]) + Math.abs(px[i + 2] - background[2]) > 24) differ++;
    }
    return differ / (w * h);
  }
  // The three.js view of both pages inside the element `view`: renderer (it
  // keeps its drawing buffer for nonBlankShare), scene on the background
  // colour, perspective camera with orbit controls, a hemisphere light and a
  // sun; render() draws, resize() fits the canvas to the element and draws.
  function threeView(view, background, o) {
    var renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    view.appendChild(renderer.domElement);
    var scene = new THREE.Scene();
    scene.background = new THREE.Color(background[0] / 255, background[1] / 255, background[2] / 255);
    var camera = new THREE.PerspectiveCamera(o.fov, 1, o.near, o.far);
    var controls = new THREE.OrbitControls(camera, renderer.domElement);
    scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8a8a, o.hemisphere));
    var sun = new THREE.DirectionalLight(0xffffff, o.sun);
    sun.position.set(o.sunAt[0], o.sunAt[1], o.sunAt[2]);
    scene.add(sun);
    function render() { renderer.render(scene, camera); }
    function resize() {
      var w = Math.max(1, view.clientWidth), h = Math.max(1, view.clientHeight);
      renderer.setSize(w, h);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
      render();
    }
    return { renderer: renderer, scene: scene, camera: camera, controls: controls, render: render, resize: resize };
  }
  function writeSelfTest(result) {
    result.errors = window.sampErrors.slice();
    var pre = element('pre', { id: 'samp-selftest' }, document.body, JSON.stringify(result));
    pre.style.display = 'none';
  }
  window.sampCommon = { bytes: bytes, typed: typed, element: element, kittiGroup: kittiGroup, fixed: fixed,
                        nonBlankShare: nonBlankShare, threeView: threeView, writeSelfTest: writeSelfTest };
})();
