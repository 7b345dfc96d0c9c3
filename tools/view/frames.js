// soadyn view: the frames a run logged (a scenario's `log: {frames: [...]}`, the run file's
// /frames), each drawn as an axis triad (x red, y green, z blue) with its name on a label, moving
// with the playback.  Their poses come in the run's JSON block (named_frames: names, the body each
// moves with, and per shown sample K x F x [px py pz qx qy qz qw]), computed by soadyn's
// frame_placement from the logged q as the bodies' are.
function SoadynNamedFrames(THREE, scene, nf, decode, length, radius) {
  'use strict';
  this.names = nf ? nf.names : [];
  this.bodies = nf ? nf.bodies : [];
  this.F = this.names.length;
  this.P = this.F ? decode(nf.pose, Float32Array) : new Float32Array(0);
  this.group = new THREE.Group();
  scene.add(this.group);
  this.triads = [];
  this.qa = new Float32Array(4);
  const shaft = new THREE.CylinderBufferGeometry(1, 1, 1, 8, 1);
  const head = new THREE.ConeBufferGeometry(1, 1, 10, 1);
  const axes = [[new THREE.Vector3(1, 0, 0), 0xd62828], [new THREE.Vector3(0, 1, 0), 0x2b9348], [new THREE.Vector3(0, 0, 1), 0x1d4ed8]];
  const Y = new THREE.Vector3(0, 1, 0);
  for (let j = 0; j < this.F; ++j) {
    const g = new THREE.Group();
    axes.forEach(([u, color]) => {
      const material = new THREE.MeshBasicMaterial({ color: color });
      const turn = new THREE.Quaternion().setFromUnitVectors(Y, u);
      const s = new THREE.Mesh(shaft, material), c = new THREE.Mesh(head, material);
      s.quaternion.copy(turn);
      s.position.copy(u).multiplyScalar(0.4 * length);
      s.scale.set(radius, 0.8 * length, radius);
      c.quaternion.copy(turn);
      c.position.copy(u).multiplyScalar(0.9 * length);
      c.scale.set(2.5 * radius, 0.2 * length, 2.5 * radius);
      g.add(s, c);
    });
    // its name, on a label that always faces the camera and is never hidden behind a body
    const canvas = document.createElement('canvas'), ctx = canvas.getContext('2d'), px = 28;
    ctx.font = px + 'px system-ui, sans-serif';
    canvas.width = Math.ceil(ctx.measureText(this.names[j]).width) + 12;
    canvas.height = px + 10;
    ctx.font = px + 'px system-ui, sans-serif';
    ctx.fillStyle = 'rgba(255, 255, 255, 0.8)';
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    ctx.fillStyle = '#1d2430';
    ctx.textBaseline = 'middle';
    ctx.fillText(this.names[j], 6, canvas.height / 2);
    const label = new THREE.Sprite(new THREE.SpriteMaterial({ map: new THREE.CanvasTexture(canvas), depthTest: false }));
    const h = 0.35 * length;
    label.scale.set(h * canvas.width / canvas.height, h, 1);
    label.center.set(0, 0);
    label.position.set(0.25 * length, 0.25 * length, 0.25 * length);
    label.renderOrder = 2;
    g.add(label);
    this.group.add(g);
    this.triads.push(g);
  }
}

// the poses at the time between shown samples k and k2 (fraction s): positions linearly,
// orientations by slerp, as the bodies'
SoadynNamedFrames.prototype.apply = function (k, k2, s) {
  const P = this.P, F = this.F;
  for (let j = 0; j < F; ++j) {
    const o = (k * F + j) * 7, o2 = (k2 * F + j) * 7, g = this.triads[j];
    g.position.set(P[o] + s * (P[o2] - P[o]), P[o + 1] + s * (P[o2 + 1] - P[o + 1]), P[o + 2] + s * (P[o2 + 2] - P[o + 2]));
    THREE.Quaternion.slerpFlat(this.qa, 0, P, o + 3, P, o2 + 3, s);
    g.quaternion.set(this.qa[0], this.qa[1], this.qa[2], this.qa[3]);
  }
};

// what is drawn: each triad's name, body, and its world position and orientation (x y z w) as
// three.js holds them after the last render
SoadynNamedFrames.prototype.state = function () {
  return this.triads.map((g, j) => {
    g.updateMatrixWorld();
    const p = new THREE.Vector3(), q = new THREE.Quaternion(), sc = new THREE.Vector3();
    g.matrixWorld.decompose(p, q, sc);
    return { name: this.names[j], body: this.bodies[j], position: p.toArray(), quaternion: q.toArray(), visible: this.group.visible && g.visible };
  });
};
