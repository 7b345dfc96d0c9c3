// soadyn view: the bodies' meshes, one per layer, rigidly skinned to a bone per body.  Used by viewer.js.
function SoadynBodies(THREE, scene, RUN, L, rSkel, rCmMax, arrowLen) {
  'use strict';
  const V = (a) => new THREE.Vector3(a[0], a[1], a[2]);
  const NB = RUN.frames.nb;
  const massMax = Math.max.apply(null, RUN.bodies.map((b) => b.mass).concat([1e-300]));

  // Every body's parts are merged into a few meshes for the whole scene, one per layer, skinned
  // rigidly (weight 1) to one bone per body: a handful of draw calls however many bodies, and a
  // frame only moves the bones.
  const palette = ['#4e79a7', '#f28e2b', '#e15759', '#76b7b2', '#59a14f', '#edc948', '#b07aa1', '#ff9da7', '#9c755f', '#8cd17d'];
  const unitSphere = new THREE.SphereBufferGeometry(1, 14, 9);
  const unitCylinder = new THREE.CylinderBufferGeometry(1, 1, 1, 10, 1, true);  // open: balls or cones end it
  const closedCylinder = new THREE.CylinderBufferGeometry(1, 1, 1, 16, 1);  // URDF cylinders
  const unitCone = new THREE.ConeBufferGeometry(1, 1, 10, 1, true);
  const unitBox = new THREE.BoxBufferGeometry(1, 1, 1);
  const Y = new THREE.Vector3(0, 1, 0);

  // rigid skinning: every vertex follows exactly one bone (skinIndex.x, weight 1), so the shaders
  // fetch one bone matrix per vertex instead of four
  THREE.ShaderChunk.skinbase_vertex = '#ifdef USE_SKINNING\n\tmat4 boneMatX = getBoneMatrix( skinIndex.x );\n#endif';
  THREE.ShaderChunk.skinning_vertex = '#ifdef USE_SKINNING\n\ttransformed = ( bindMatrixInverse * ( boneMatX * ( bindMatrix * vec4( transformed, 1.0 ) ) ) ).xyz;\n#endif';
  THREE.ShaderChunk.skinnormal_vertex = '#ifdef USE_SKINNING\n\tmat4 skinMatrix = bindMatrixInverse * boneMatX * bindMatrix;\n' +
    '\tobjectNormal = vec4( skinMatrix * vec4( objectNormal, 0.0 ) ).xyz;\n\t#ifdef USE_TANGENT\n' +
    '\t\tobjectTangent = vec4( skinMatrix * vec4( objectTangent, 0.0 ) ).xyz;\n\t#endif\n#endif';
  const smallSphere = new THREE.SphereBufferGeometry(1, 10, 6);  // the skeleton's joints and ends

  function Batch() { this.pos = []; this.nor = []; this.col = []; this.bone = []; this.index = []; }
  // append geometry g, placed by matrix M (body frame), coloured, bound to bone b
  Batch.prototype.add = function (g, M, color, b) {
    const P = g.attributes.position.array, N = g.attributes.normal.array, base = this.bone.length;
    const nm = new THREE.Matrix3().getNormalMatrix(M), v = new THREE.Vector3();
    for (let j = 0; j < P.length / 3; ++j) {
      v.set(P[3 * j], P[3 * j + 1], P[3 * j + 2]).applyMatrix4(M);
      this.pos.push(v.x, v.y, v.z);
      v.set(N[3 * j], N[3 * j + 1], N[3 * j + 2]).applyMatrix3(nm).normalize();
      this.nor.push(v.x, v.y, v.z);
      this.col.push(color.r, color.g, color.b);
      this.bone.push(b);
    }
    if (g.index) g.index.array.forEach((j) => this.index.push(base + j));
    else for (let j = 0; j < P.length / 3; ++j) this.index.push(base + j);
  };
  Batch.prototype.mesh = function (skeleton, material) {
    const geom = new THREE.BufferGeometry(), n = this.bone.length;
    const index = new Float32Array(4 * n), weight = new Float32Array(4 * n);
    for (let k = 0; k < n; ++k) { index[4 * k] = this.bone[k]; weight[4 * k] = 1; }
    geom.setAttribute('position', new THREE.Float32BufferAttribute(this.pos, 3));
    geom.setAttribute('normal', new THREE.Float32BufferAttribute(this.nor, 3));
    geom.setAttribute('color', new THREE.Float32BufferAttribute(this.col, 3));
    geom.setAttribute('skinIndex', new THREE.BufferAttribute(index, 4));
    geom.setAttribute('skinWeight', new THREE.BufferAttribute(weight, 4));
    geom.setIndex(n > 65535 ? new THREE.Uint32BufferAttribute(this.index, 1) : new THREE.Uint16BufferAttribute(this.index, 1));
    material.skinning = true;
    material.vertexColors = THREE.VertexColors;
    const m = new THREE.SkinnedMesh(geom, material);
    m.bind(skeleton, new THREE.Matrix4());
    m.frustumCulled = false;  // its bounds are those of the bind pose
    return m;
  };
  const compose = (p, q, s) => new THREE.Matrix4().compose(p, q, s);
  const S1 = new THREE.Vector3(1, 1, 1), Q1 = new THREE.Quaternion();
  // a primitive of the scene file (box / cylinder along z / sphere) in its frame
  function addShape(batch, sh, color, b) {
    const M = compose(V(sh.p), new THREE.Quaternion().fromArray(sh.q), S1);
    if (sh.kind === 'box') {
      const e = sh.size.map((x) => Math.max(x, 1e-3 * L));
      batch.add(unitBox, M.multiply(compose(new THREE.Vector3(), Q1, V(e))), color, b);
    } else if (sh.kind === 'cylinder') {  // URDF: radius, length along z; three.js: along y
      const r = new THREE.Quaternion().setFromAxisAngle(new THREE.Vector3(1, 0, 0), Math.PI / 2);
      batch.add(closedCylinder, M.multiply(compose(new THREE.Vector3(), r, new THREE.Vector3(sh.size[0], sh.size[1], sh.size[0]))), color, b);
    } else {
      batch.add(unitSphere, M.multiply(compose(new THREE.Vector3(), Q1, new THREE.Vector3(1, 1, 1).multiplyScalar(sh.size[0]))), color, b);
    }
  }
  // a cylinder of radius r from a to b (and a cone on it when cone = [radius, length])
  function addRod(batch, a, c, r, color, b, cone) {
    const d = c.clone().sub(a), len = d.length(), u = d.clone().normalize();
    const q = new THREE.Quaternion().setFromUnitVectors(Y, u);
    const shaft = cone ? len - cone[1] : len;
    batch.add(unitCylinder, compose(a.clone().addScaledVector(u, 0.5 * shaft), q, new THREE.Vector3(r, shaft, r)), color, b);
    if (cone) batch.add(unitCone, compose(a.clone().addScaledVector(u, shaft + 0.5 * cone[1]), q, new THREE.Vector3(cone[0], cone[1], cone[0])), color, b);
  }
  const ball = (batch, p, r, color, b, geom) => batch.add(geom || unitSphere, compose(p, Q1, new THREE.Vector3(r, r, r)), color, b);

  const bones = RUN.bodies.map(() => new THREE.Bone());
  const boneRoot = new THREE.Group();
  bones.forEach((b) => boneRoot.add(b));
  scene.add(boneRoot);
  const skeleton = new THREE.Skeleton(bones, bones.map(() => new THREE.Matrix4()));
  const batches = { skeleton: new Batch(), cm: new Batch(), boxes: new Batch(), visuals: new Batch(), axes: new Batch() };
  const O = new THREE.Vector3();
  RUN.bodies.forEach((b, i) => {
    const color = new THREE.Color(palette[i % palette.length]), dark = color.clone().multiplyScalar(0.55);
    // skeleton: capsules from the joint to the children's joints, a ball at the joint
    // (a segment to a child ends in the child's joint ball; only a leaf's needs a ball of its own)
    const leaf = !RUN.bodies.some((c) => c.parent === i);
    b.segments.forEach((sg) => {
      addRod(batches.skeleton, O, V(sg), rSkel, color, i);
      if (leaf) ball(batches.skeleton, V(sg), rSkel, color, i, smallSphere);
    });
    ball(batches.skeleton, O, 1.4 * rSkel, color, i, smallSphere);
    // centre of mass: a sphere whose volume is proportional to the mass
    ball(batches.cm, V(b.com), rCmMax * Math.cbrt(b.mass / massMax), dark, i, NB > 16 ? smallSphere : unitSphere);
    // the uniform box with the body's mass and principal moments of inertia
    if (V(b.box.size).length() > 1e-9) addShape(batches.boxes, b.box, color, i);
    // URDF visual primitives
    b.visuals.forEach((sh) => addShape(batches.visuals, sh, sh.color ? new THREE.Color(sh.color) : color, i));
    // joint axis: an arrow through the joint (revolute: orange, prismatic: purple, planar: teal,
    // along the plane's normal); free: a triad; ball: a ring
    const rA = 0.22 * rSkel, head = [0.1 * arrowLen, 0.25 * arrowLen];
    const axisColor = { revolute: 0xd9480f, prismatic: 0x7048e8, planar: 0x0c8599 }[b.type];
    if (axisColor !== undefined && V(b.axis).length() > 0) {  // planar: the plane's normal
      const u = V(b.axis).normalize();
      addRod(batches.axes, u.clone().multiplyScalar(-0.5 * arrowLen), u.clone().multiplyScalar(arrowLen), rA,
        new THREE.Color(axisColor), i, head);
    } else if (b.type === 'free') {
      [[1, 0, 0, 0xd62828], [0, 1, 0, 0x2b9348], [0, 0, 1, 0x1d4ed8]].forEach((a) =>
        addRod(batches.axes, O, new THREE.Vector3(a[0], a[1], a[2]).multiplyScalar(1.2 * arrowLen), rA, new THREE.Color(a[3]), i, head));
    } else {  // ball and other multi-axis joints: a ring around the joint
      batches.axes.add(new THREE.TorusBufferGeometry(2.4, 0.35, 8, 24), compose(O, Q1, new THREE.Vector3(rSkel, rSkel, rSkel)), dark, i);
    }
  });
  const layers = {
    skeleton: [batches.skeleton.mesh(skeleton, new THREE.MeshLambertMaterial())],
    cm: [batches.cm.mesh(skeleton, new THREE.MeshLambertMaterial())],
    boxes: [batches.boxes.mesh(skeleton, new THREE.MeshLambertMaterial({ transparent: true, opacity: 0.28, depthWrite: false }))],
    visuals: [batches.visuals.mesh(skeleton, new THREE.MeshLambertMaterial())],
    axes: [batches.axes.mesh(skeleton, new THREE.MeshLambertMaterial())],
  };
  const bodyMeshes = [].concat(layers.skeleton, layers.cm, layers.boxes, layers.visuals, layers.axes);
  bodyMeshes.forEach((m) => scene.add(m));
  layers.boxes[0].renderOrder = 1;  // translucent, after the rest
  const visualCount = RUN.bodies.reduce((a, b) => a + b.visuals.length, 0) + RUN.world_visuals.length;
  if (RUN.world_visuals.length) {
    const wb = new Batch();
    const world = new THREE.Bone();
    scene.add(world);
    RUN.world_visuals.forEach((sh) => addShape(wb, sh, new THREE.Color(sh.color || '#9aa3ad'), 0));
    const wm = wb.mesh(new THREE.Skeleton([world], [new THREE.Matrix4()]), new THREE.MeshLambertMaterial());
    scene.add(wm);
    layers.visuals.push(wm);
  }
  this.bones = bones;              // one per body: a frame moves only these
  this.layers = layers;            // skeleton, cm, boxes, visuals, axes: what each option shows
  this.meshes = bodyMeshes;        // the bodies' meshes (not the world's visuals)
  this.visualCount = visualCount;  // URDF visual primitives, the world's included
}
