// soadyn view: the model's mesh files, each read once by three.js's own loaders (STLLoader,
// OBJLoader, ColladaLoader: inlined only in a page with a file of their format) from the base64
// blocks #soadyn-mesh-K that `soadyn view` wrote.  Each becomes parts to draw, or the reason it
// cannot be drawn, for the page's note: a bad file never throws here and never logs an error.
// Used by bodies.js.
function SoadynMeshes(THREE, list) {
  'use strict';
  // a 1 x 1 transparent image: what a Collada file's textures load instead of their files (the
  // page requests nothing; the meshes are drawn in their materials' colours)
  const pixel = 'data:image/gif;base64,R0lGODlhAQABAIAAAAAAAP///yH5BAEAAAAALAAAAAABAAEAAAIBRAA7';
  const manager = new THREE.LoadingManager();
  manager.setURLModifier(() => pixel);

  function bytesOf(k) {
    const bin = atob(document.getElementById('soadyn-mesh-' + k).textContent);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
    return bytes;
  }
  const text = (bytes) => new TextDecoder().decode(bytes);

  // fn() with what it says through console.error kept as the reason it failed (a loader's way of
  // saying a file is malformed), not logged
  function quietly(fn) {
    const saved = console.error;
    let said = null;
    console.error = function () { if (said === null) said = Array.prototype.join.call(arguments, ' '); };
    try {
      return { value: fn(), said: said };
    } finally {
      console.error = saved;
    }
  }

  // the meshes under an object the OBJ or Collada loader made: geometry, placement in the file,
  // and (a Collada file with materials of its own) a colour per vertex from its materials
  function partsOf(root, ownColors) {
    const parts = [];
    root.updateMatrixWorld(true);
    root.traverse((o) => {
      if (!o.isMesh || !o.geometry || !o.geometry.isBufferGeometry) return;
      const g = o.geometry;
      if (!g.attributes.normal) g.computeVertexNormals();
      let colors = null;
      if (ownColors) {
        const materials = Array.isArray(o.material) ? o.material : [o.material];
        const n = g.attributes.position.count, idx = g.index ? g.index.array : null;
        colors = new Float32Array(3 * n).fill(1);
        const groups = g.groups.length ? g.groups : [{ start: 0, count: idx ? idx.length : n, materialIndex: 0 }];
        groups.forEach((gr) => {
          const m = materials[gr.materialIndex || 0], c = m && m.color ? m.color : new THREE.Color(1, 1, 1);
          for (let j = gr.start; j < Math.min(gr.start + gr.count, idx ? idx.length : n); ++j) {
            const v = idx ? idx[j] : j;
            colors[3 * v] = c.r; colors[3 * v + 1] = c.g; colors[3 * v + 2] = c.b;
          }
        });
      }
      parts.push({ geometry: g, matrix: o.matrixWorld.clone(), colors: colors });
    });
    return parts;
  }

  const load = {
    stl: (bytes) => [{ geometry: new THREE.STLLoader().parse(bytes.buffer), matrix: new THREE.Matrix4(), colors: null }],
    obj: (bytes) => partsOf(new THREE.OBJLoader().parse(text(bytes)), false),
    // a URDF's Collada file is drawn in its own axes, whatever its up_axis (as ROS tools do:
    // the loader's turn of a Z_UP file to three.js's Y up is undone), scaled by its <unit>
    dae: (bytes) => {
      const dae = new THREE.ColladaLoader(manager).parse(text(bytes), '');
      if (!dae || !dae.scene) return null;
      dae.scene.quaternion.set(0, 0, 0, 1);
      return partsOf(dae.scene, Object.keys(dae.library.materials || {}).length > 0);
    },
    // an MJCF mesh as MuJoCo compiled it: float32 vertices, uint32 triangles; drawn flat-shaded
    arrays: (bytes, f) => {
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(bytes.buffer, 0, 3 * f.vertices), 3));
      g.setIndex(new THREE.BufferAttribute(new Uint32Array(bytes.buffer, 12 * f.vertices, 3 * f.triangles), 1));
      const flat = g.toNonIndexed();
      flat.computeVertexNormals();
      return [{ geometry: flat, matrix: new THREE.Matrix4(), colors: null }];
    },
  };

  // why parts cannot be drawn ('' if they can): no triangle, or a coordinate that is not finite
  function problem(parts) {
    let triangles = 0;
    for (const p of parts) {
      const P = p.geometry.attributes.position;
      if (!P) continue;
      triangles += (p.geometry.index ? p.geometry.index.count : P.count) / 3 | 0;
      for (let i = 0; i < P.array.length; ++i) if (!isFinite(P.array[i])) return 'a vertex coordinate is not a finite number';
    }
    return triangles > 0 ? '' : 'no triangles in it';
  }

  const label = { stl: 'the STL loader', obj: 'the OBJ loader', dae: 'the Collada loader', arrays: 'the compiled mesh' };
  this.files = list.map((f, k) => {
    const out = { name: f.name, format: f.format, parts: null, error: f.error };
    if (out.error) return out;
    const failed = (why) => (label[f.format] || f.format) + ': ' + why;
    try {
      if (!load[f.format]) throw new Error('no loader for the format ' + f.format);
      const r = quietly(() => load[f.format](bytesOf(k), f));
      const why = r.value ? problem(r.value) : 'nothing read';
      if (why) out.error = failed(why + (r.said ? ' (' + r.said.trim() + ')' : ''));
      else out.parts = r.value;
    } catch (e) {
      out.error = failed(e && e.message ? e.message : String(e));
    }
    return out;
  });
}
