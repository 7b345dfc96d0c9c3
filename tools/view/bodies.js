// soadyn view: the bodies' meshes, one per layer, rigidly skinned to a bone per body, and which
// body is drawn under the pointer.  Used by viewer.js; `meshes` is meshes.js's SoadynMeshes.
function SoadynBodies(THREE, scene, RUN, L, rSkel, rCmMax, arrowLen, meshes) {
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

  // a batch of parts: geometry g placed by matrix M (body frame), coloured (one colour, or one per
  // vertex), bound to bone b; merged into one skinned mesh by mesh().  Each body's triangles stay
  // together, so a hit can be traced back to its body (pick).
  function Batch() { this.parts = []; this.nv = 0; this.ni = 0; }
  Batch.prototype.add = function (g, M, color, b, colors) {
    const n = g.attributes.position.count;
    this.parts.push({ g: g, M: M.clone(), color: color, b: b, colors: colors || null });
    this.nv += n;
    this.ni += g.index ? g.index.count : n;
  };
  Batch.prototype.mesh = function (skeleton, material) {
    const n = this.nv, pos = new Float32Array(3 * n), nor = new Float32Array(3 * n), col = new Float32Array(3 * n);
    const index = new Float32Array(4 * n), weight = new Float32Array(4 * n), tri = n > 65535 ? new Uint32Array(this.ni) : new Uint16Array(this.ni);
    const v = new THREE.Vector3(), nm = new THREE.Matrix3(), ranges = [];
    let at = 0, it = 0;
    this.parts.forEach((p) => {
      const P = p.g.attributes.position, N = p.g.attributes.normal, m = P.count, base = at;
      nm.getNormalMatrix(p.M);
      for (let j = 0; j < m; ++j, ++at) {
        v.fromBufferAttribute(P, j).applyMatrix4(p.M);
        pos[3 * at] = v.x; pos[3 * at + 1] = v.y; pos[3 * at + 2] = v.z;
        v.fromBufferAttribute(N, j).applyMatrix3(nm).normalize();
        nor[3 * at] = v.x; nor[3 * at + 1] = v.y; nor[3 * at + 2] = v.z;
        if (p.colors) { col[3 * at] = p.colors[3 * j]; col[3 * at + 1] = p.colors[3 * j + 1]; col[3 * at + 2] = p.colors[3 * j + 2]; }
        else { col[3 * at] = p.color.r; col[3 * at + 1] = p.color.g; col[3 * at + 2] = p.color.b; }
        index[4 * at] = p.b; weight[4 * at] = 1;
      }
      // a mirroring placement (a negative scale) turns the triangles over: their corners swapped back
      const flip = p.M.determinant() < 0, start = it, idx = p.g.index ? p.g.index.array : null, count = idx ? idx.length : m;
      for (let j = 0; j < count; j += 3) {
        const a = idx ? idx[j] : j, b = idx ? idx[j + 1] : j + 1, c = idx ? idx[j + 2] : j + 2;
        tri[it++] = base + a; tri[it++] = base + (flip ? c : b); tri[it++] = base + (flip ? b : c);
      }
      const last = ranges[ranges.length - 1];
      if (last && last.body === p.b && last.end === start) last.end = it;
      else ranges.push({ body: p.b, start: start, end: it });
    });
    // each body's bounding sphere, in its frame: a ray that misses it skips its triangles
    ranges.forEach((r) => {
      const box = new THREE.Box3();
      for (let j = r.start; j < r.end; ++j) box.expandByPoint(v.fromArray(pos, 3 * tri[j]));
      r.sphere = box.getBoundingSphere(new THREE.Sphere());
    });
    const geom = new THREE.BufferGeometry();
    geom.setAttribute('position', new THREE.BufferAttribute(pos, 3));
    geom.setAttribute('normal', new THREE.BufferAttribute(nor, 3));
    geom.setAttribute('color', new THREE.BufferAttribute(col, 3));
    geom.setAttribute('skinIndex', new THREE.BufferAttribute(index, 4));
    geom.setAttribute('skinWeight', new THREE.BufferAttribute(weight, 4));
    geom.setIndex(new THREE.BufferAttribute(tri, 1));
    material.skinning = true;
    material.vertexColors = THREE.VertexColors;
    const mesh = new THREE.SkinnedMesh(geom, material);
    mesh.bind(skeleton, new THREE.Matrix4());
    mesh.frustumCulled = false;  // its bounds are those of the bind pose
    mesh.userData.ranges = ranges;
    return mesh;
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
  // a mesh visual: its file's parts at the visual's origin and scale, in the visual's colour (a
  // Collada file with materials: theirs); false if the file cannot be drawn
  function addMesh(batch, sh, color, b) {
    const file = meshes.files[sh.mesh];
    if (!file || !file.parts) return false;
    const M = compose(V(sh.p), new THREE.Quaternion().fromArray(sh.q), V(sh.size));
    file.parts.forEach((part) => batch.add(part.geometry, M.clone().multiply(part.matrix), color, b, part.colors));
    return true;
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
  const batches = { skeleton: new Batch(), cm: new Batch(), boxes: new Batch(), visuals: new Batch(), meshes: new Batch(), axes: new Batch() };
  const O = new THREE.Vector3();
  let visualCount = 0, meshCount = 0;
  const fellBack = [];  // bodies drawn in their default shape for a mesh that could not be
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
    const hasBox = V(b.box.size).length() > 1e-9;
    if (hasBox) addShape(batches.boxes, b.box, color, i);
    // the visuals: primitives, and meshes (double-sided: a mesh's triangles may face either way);
    // a mesh that cannot be drawn leaves the body its default shape, its inertia box, among them
    let failed = false;
    b.visuals.forEach((sh) => {
      const c = sh.color ? new THREE.Color(sh.color) : color;
      if (sh.kind !== 'mesh') { addShape(batches.visuals, sh, c, i); visualCount += 1; }
      else if (addMesh(batches.meshes, sh, c, i)) meshCount += 1;
      else failed = true;
    });
    if (failed) {
      fellBack.push(i);
      if (hasBox) addShape(batches.visuals, b.box, color, i);
    }
    // joint axis: an arrow through the joint (revolute: orange, prismatic: purple, helical: green,
    // planar: teal, along the plane's normal); free: a triad; ball: a ring
    const rA = 0.22 * rSkel, head = [0.1 * arrowLen, 0.25 * arrowLen];
    const axisColor = { revolute: 0xd9480f, prismatic: 0x7048e8, helical: 0x2b8a3e, planar: 0x0c8599 }[b.type];
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
  const lambert = (o) => new THREE.MeshLambertMaterial(o);
  const layers = {
    skeleton: [batches.skeleton.mesh(skeleton, lambert())],
    cm: [batches.cm.mesh(skeleton, lambert())],
    boxes: [batches.boxes.mesh(skeleton, lambert({ transparent: true, opacity: 0.28, depthWrite: false }))],
    visuals: [batches.visuals.mesh(skeleton, lambert()), batches.meshes.mesh(skeleton, lambert({ side: THREE.DoubleSide }))],
    axes: [batches.axes.mesh(skeleton, lambert())],
  };
  const bodyMeshes = [].concat(layers.skeleton, layers.cm, layers.boxes, layers.visuals, layers.axes);
  bodyMeshes.forEach((m) => scene.add(m));
  layers.boxes[0].renderOrder = 1;  // translucent, after the rest
  // the visuals of links welded to the world: bound to a bone that never moves
  let worldFailed = false;
  if (RUN.world_visuals.length) {
    const wb = new Batch(), wm = new Batch();
    const world = new THREE.Bone();
    scene.add(world);
    RUN.world_visuals.forEach((sh) => {
      const c = new THREE.Color(sh.color || '#9aa3ad');
      if (sh.kind !== 'mesh') { addShape(wb, sh, c, 0); visualCount += 1; }
      else if (addMesh(wm, sh, c, 0)) meshCount += 1;
      else worldFailed = true;
    });
    const ws = new THREE.Skeleton([world], [new THREE.Matrix4()]);
    [wb.mesh(ws, lambert()), wm.mesh(ws, lambert({ side: THREE.DoubleSide }))].forEach((m) => {
      m.userData.ranges = [];  // not a body's: never picked
      scene.add(m);
      layers.visuals.push(m);
    });
  }
  this.bones = bones;              // one per body: a frame moves only these
  this.layers = layers;            // skeleton, cm, boxes, visuals, axes: what each option shows
  this.meshes = bodyMeshes;        // the bodies' meshes (not the world's visuals)
  this.visualCount = visualCount;  // visual primitives drawn, the world's included
  this.meshCount = meshCount;      // mesh visuals drawn, the world's included
  this.fellBack = fellBack;        // bodies with a mesh that could not be drawn
  this.worldFellBack = worldFailed;
}

// The body drawn nearest along a ray (world coordinates) among the shown layers: {body, distance},
// or null; the opaque layers first, the translucent ones (the inertia boxes) only where no opaque
// one is hit.  The meshes are skinned, so their buffers hold every body at its bind pose
// (identity): each body's triangles are tested against the ray brought into that body's frame.
SoadynBodies.prototype.pick = function (ray) {
  const shown = this.meshes.filter((m) => m.visible && m.userData.ranges);
  return this.nearest(ray, shown.filter((m) => !m.material.transparent)) ||
    this.nearest(ray, shown.filter((m) => m.material.transparent));
};
SoadynBodies.prototype.nearest = function (ray, meshes) {
  const inv = new THREE.Matrix4(), local = new THREE.Ray();
  const e1 = [0, 0, 0], e2 = [0, 0, 0], pv = [0, 0, 0], tv = [0, 0, 0], qv = [0, 0, 0];
  let best = null;
  meshes.forEach((m) => {
    const pos = m.geometry.attributes.position.array, tri = m.geometry.index.array;
    m.userData.ranges.forEach((r) => {
      local.copy(ray).applyMatrix4(inv.getInverse(this.bones[r.body].matrixWorld));
      if (!local.intersectsSphere(r.sphere)) return;
      const o = local.origin, d = local.direction;
      // Möller–Trumbore, both faces, on the raw arrays
      for (let j = r.start; j < r.end; j += 3) {
        const a = 3 * tri[j], b = 3 * tri[j + 1], c = 3 * tri[j + 2];
        for (let k = 0; k < 3; ++k) { e1[k] = pos[b + k] - pos[a + k]; e2[k] = pos[c + k] - pos[a + k]; tv[k] = o.getComponent(k) - pos[a + k]; }
        pv[0] = d.y * e2[2] - d.z * e2[1]; pv[1] = d.z * e2[0] - d.x * e2[2]; pv[2] = d.x * e2[1] - d.y * e2[0];
        const det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
        if (Math.abs(det) < 1e-18) continue;
        const u = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) / det;
        if (u < 0 || u > 1) continue;
        qv[0] = tv[1] * e1[2] - tv[2] * e1[1]; qv[1] = tv[2] * e1[0] - tv[0] * e1[2]; qv[2] = tv[0] * e1[1] - tv[1] * e1[0];
        const w = (d.x * qv[0] + d.y * qv[1] + d.z * qv[2]) / det;
        if (w < 0 || u + w > 1) continue;
        const t = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) / det;  // the bones are rigid: a world distance
        if (t > 0 && (!best || t < best.distance)) best = { body: r.body, distance: t };
      }
    });
  });
  return best;
};
