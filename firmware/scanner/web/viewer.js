// The cloud viewer: a PLY parser (ascii, binary little/big endian; any
// scalar vertex properties) and a three.js r111 point view with orbit
// controls. The scanner writes float x y z (mm, camera frame: z away from
// the camera, y down), float quality (fringe modulation), float intensity
// and uint pixel (firmware/core/src/point_cloud.cpp).
'use strict';

const FppViewer = (function () {
  // Browsers slow down past a few hundred thousand points on phones.
  const MAX_POINTS = 300000;
  const CLEAR_COLOUR = 0x10141a;

  // PLY scalar types: byte size and DataView reader.
  const PLY_TYPES = {
    char: [1, 'getInt8'], int8: [1, 'getInt8'],
    uchar: [1, 'getUint8'], uint8: [1, 'getUint8'],
    short: [2, 'getInt16'], int16: [2, 'getInt16'],
    ushort: [2, 'getUint16'], uint16: [2, 'getUint16'],
    int: [4, 'getInt32'], int32: [4, 'getInt32'],
    uint: [4, 'getUint32'], uint32: [4, 'getUint32'],
    float: [4, 'getFloat32'], float32: [4, 'getFloat32'],
    double: [8, 'getFloat64'], float64: [8, 'getFloat64'],
  };

  // ---- PLY parsing -------------------------------------------------------

  // Where the header ends: the byte after "end_header" and its line break.
  function findHeaderEnd(bytes) {
    const limit = Math.min(bytes.length, 1 << 20);
    const head = new TextDecoder('latin1').decode(bytes.subarray(0, limit));
    const at = head.search(/end_header\r?\n/);
    if (at < 0) throw new Error('PLY: no end_header in the first MiB');
    const lineEnd = head.indexOf('\n', at);
    return { text: head.slice(0, at), bodyStart: lineEnd + 1 };
  }

  // The header: format and the elements in file order, each with its
  // properties (name, type, or list with count and item types).
  function parseHeader(text) {
    const lines = text.split(/\r?\n/);
    if (lines[0].trim() !== 'ply') throw new Error('PLY: the file does not start with "ply"');
    const header = { format: null, elements: [] };
    for (const raw of lines.slice(1)) {
      const words = raw.trim().split(/\s+/);
      const keyword = words[0];
      if (keyword === 'format') {
        header.format = words[1];
      } else if (keyword === 'element') {
        const count = Number(words[2]);
        if (!Number.isInteger(count) || count < 0) throw new Error('PLY: bad count in "' + raw + '"');
        header.elements.push({ name: words[1], count: count, properties: [] });
      } else if (keyword === 'property') {
        const element = header.elements[header.elements.length - 1];
        if (!element) throw new Error('PLY: property before any element');
        if (words[1] === 'list') {
          element.properties.push({ name: words[4], list: true, countType: words[2], type: words[3] });
        } else {
          if (!PLY_TYPES[words[1]]) throw new Error('PLY: unknown property type "' + words[1] + '"');
          element.properties.push({ name: words[2], list: false, type: words[1] });
        }
      }
      // comment, obj_info and anything else: not needed to draw.
    }
    if (!['ascii', 'binary_little_endian', 'binary_big_endian'].includes(header.format))
      throw new Error('PLY: unsupported format "' + header.format + '"');
    return header;
  }

  // Every `stride`-th vertex's scalar properties, as one Float32Array per
  // property name ({x, y, z, quality, ...}).
  function parsePly(buffer, maxPoints) {
    const bytes = new Uint8Array(buffer);
    const { text, bodyStart } = findHeaderEnd(bytes);
    const header = parseHeader(text);
    const vertexIndex = header.elements.findIndex(e => e.name === 'vertex');
    if (vertexIndex < 0) throw new Error('PLY: no vertex element');
    const vertex = header.elements[vertexIndex];
    for (const axis of ['x', 'y', 'z'])
      if (!vertex.properties.some(p => p.name === axis && !p.list))
        throw new Error('PLY: the vertex element has no ' + axis + ' property');
    if (vertex.properties.some(p => p.list))
      throw new Error('PLY: list properties in the vertex element are not supported');
    const stride = Math.max(1, Math.ceil(vertex.count / (maxPoints || MAX_POINTS)));
    const kept = Math.ceil(vertex.count / stride);
    const columns = {};
    for (const p of vertex.properties) columns[p.name] = new Float32Array(kept);
    if (header.format === 'ascii')
      readAscii(bytes, bodyStart, header, vertexIndex, stride, columns);
    else
      readBinary(buffer, bodyStart, header, vertexIndex, stride, columns);
    return { total: vertex.count, count: kept, stride: stride, columns: columns,
             properties: vertex.properties.map(p => p.name), format: header.format };
  }

  function readBinary(buffer, offset, header, vertexIndex, stride, columns) {
    const little = header.format === 'binary_little_endian';
    const view = new DataView(buffer);
    // Skip the elements before the vertices (fixed-size records only).
    for (const element of header.elements.slice(0, vertexIndex)) {
      if (element.properties.some(p => p.list))
        throw new Error('PLY: element "' + element.name + '" before the vertices has list properties');
      offset += element.count * recordSize(element);
    }
    const vertex = header.elements[vertexIndex];
    const size = recordSize(vertex);
    if (offset + vertex.count * size > buffer.byteLength)
      throw new Error('PLY: the file is shorter than its ' + vertex.count + ' vertices');
    const fields = [];
    let at = 0;
    for (const p of vertex.properties) {
      fields.push({ column: columns[p.name], at: at, read: PLY_TYPES[p.type][1] });
      at += PLY_TYPES[p.type][0];
    }
    let out = 0;
    for (let i = 0; i < vertex.count; i += stride, ++out) {
      const base = offset + i * size;
      for (const f of fields) f.column[out] = view[f.read](base + f.at, little);
    }
  }

  function recordSize(element) {
    return element.properties.reduce((sum, p) => sum + PLY_TYPES[p.type][0], 0);
  }

  function readAscii(bytes, offset, header, vertexIndex, stride, columns) {
    const body = new TextDecoder('latin1').decode(bytes.subarray(offset));
    const lines = body.split('\n');
    let line = 0;
    // Each record is one line, whatever its properties.
    for (const element of header.elements.slice(0, vertexIndex)) line += element.count;
    const vertex = header.elements[vertexIndex];
    const names = vertex.properties.map(p => p.name);
    let out = 0;
    for (let i = 0; i < vertex.count; i += stride, ++out) {
      const text = lines[line + i];
      if (text === undefined) throw new Error('PLY: the file is shorter than its ' + vertex.count + ' vertices');
      const words = text.trim().split(/\s+/);
      if (words.length < names.length) throw new Error('PLY: vertex ' + i + ' has too few values');
      for (let k = 0; k < names.length; ++k) columns[names[k]][out] = Number(words[k]);
    }
  }

  // ---- colours -----------------------------------------------------------

  // Google's Turbo colour map, polynomial approximation; t in [0, 1].
  function turbo(t, rgb, at) {
    t = Math.min(1, Math.max(0, t));
    const t2 = t * t, t3 = t2 * t, t4 = t3 * t, t5 = t4 * t;
    rgb[at] = clamp01(0.13572138 + 4.61539260 * t - 42.66032258 * t2 + 132.13108234 * t3 - 152.94239396 * t4 + 59.28637943 * t5);
    rgb[at + 1] = clamp01(0.09140261 + 2.19418839 * t + 4.84296658 * t2 - 14.18503333 * t3 + 4.27729857 * t4 + 2.82956604 * t5);
    rgb[at + 2] = clamp01(0.10667330 + 12.64194608 * t - 60.58204836 * t2 + 110.36276771 * t3 - 89.90310912 * t4 + 27.34824973 * t5);
  }

  function clamp01(v) { return v < 0 ? 0 : v > 1 ? 1 : v; }

  // The 1st and 99th percentiles of finite values: a few outliers must not
  // squeeze every other point into one colour.
  function robustRange(values) {
    const step = Math.max(1, Math.floor(values.length / 20000));
    const sample = [];
    for (let i = 0; i < values.length; i += step) if (Number.isFinite(values[i])) sample.push(values[i]);
    if (sample.length === 0) return [0, 1];
    sample.sort((a, b) => a - b);
    const lo = sample[Math.floor(0.01 * (sample.length - 1))];
    const hi = sample[Math.ceil(0.99 * (sample.length - 1))];
    return hi > lo ? [lo, hi] : [lo, lo + 1];
  }

  function colourArray(values, colours) {
    const [lo, hi] = robustRange(values);
    const scale = 1 / (hi - lo);
    for (let i = 0; i < values.length; ++i) turbo((values[i] - lo) * scale, colours, 3 * i);
    return [lo, hi];
  }

  // ---- the view ----------------------------------------------------------

  // A viewer in `container`; `onMessage(text)` reports problems to the page.
  function create(container, onMessage) {
    let renderer;
    try {
      // preserveDrawingBuffer: the page's test reads the canvas back.
      renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
    } catch (e) {
      onMessage('WebGL is not available in this browser: ' + e.message);
      return null;
    }
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    renderer.setClearColor(CLEAR_COLOUR, 1);
    container.appendChild(renderer.domElement);

    const scene = new THREE.Scene();
    const camera = new THREE.PerspectiveCamera(45, 1, 1, 10000);
    const controls = new THREE.OrbitControls(camera, renderer.domElement);
    controls.screenSpacePanning = true;
    let points = null;
    let cloud = null;
    let userMoved = false; // until the user turns the view, a resize re-frames the cloud

    function render() { renderer.render(scene, camera); }
    controls.addEventListener('change', render);
    controls.addEventListener('start', () => { userMoved = true; });

    function resize() {
      const w = Math.max(1, container.clientWidth), h = Math.max(1, container.clientHeight);
      renderer.setSize(w, h, false);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
      if (points && !userMoved && points.geometry.getAttribute('position').count > 0) frame(points.geometry);
      render();
    }
    if (window.ResizeObserver) new ResizeObserver(resize).observe(container);
    else window.addEventListener('resize', resize);
    resize();

    // Looks along +z with y down, as the scanner's camera does, at the
    // cloud's bounding box: its near face fills the view with a margin.
    function frame(geometry) {
      geometry.computeBoundingBox();
      const box = geometry.boundingBox;
      const centre = box.getCenter(new THREE.Vector3());
      const half = box.getSize(new THREE.Vector3()).multiplyScalar(0.5);
      const tanHalfFov = Math.tan(camera.fov * Math.PI / 360);
      const fit = Math.max(half.y / tanHalfFov, half.x / (tanHalfFov * camera.aspect), 1e-3);
      const distance = half.z + 1.1 * fit;
      const reach = distance + half.length();
      camera.near = reach / 1000;
      camera.far = reach * 10;
      camera.up.set(0, -1, 0);
      camera.position.set(centre.x, centre.y, centre.z - distance);
      camera.updateProjectionMatrix();
      controls.target.copy(centre);
      controls.update();
    }

    function applyColours(mode) {
      const values = mode === 'quality' && cloud.columns.quality ? cloud.columns.quality : cloud.columns.z;
      const attribute = points.geometry.getAttribute('color');
      const range = colourArray(values, attribute.array);
      attribute.needsUpdate = true;
      return range;
    }

    // Draws a parsed cloud; returns what was drawn.
    function show(parsed, scanId, mode) {
      if (points) {
        scene.remove(points);
        points.geometry.dispose();
        points.material.dispose();
      }
      cloud = parsed;
      const n = parsed.count;
      const positions = new Float32Array(3 * n);
      const { x, y, z } = parsed.columns;
      for (let i = 0; i < n; ++i) {
        positions[3 * i] = x[i];
        positions[3 * i + 1] = y[i];
        positions[3 * i + 2] = z[i];
      }
      const geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
      geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(3 * n), 3));
      // Screen-sized points: the cloud stays solid at any zoom on any screen.
      const material = new THREE.PointsMaterial({
        size: 2 * (window.devicePixelRatio || 1), sizeAttenuation: false,
        vertexColors: THREE.VertexColors,
      });
      points = new THREE.Points(geometry, material);
      scene.add(points);
      const range = applyColours(mode);
      userMoved = false;
      if (n > 0) frame(geometry);
      render();
      const drawn = { points: n, total: parsed.total, scanId: scanId, colourBy: mode, range: range,
                      clearColour: '#' + CLEAR_COLOUR.toString(16).padStart(6, '0') };
      window.fppViewer = drawn;
      return drawn;
    }

    function recolour(mode) {
      if (!points) return null;
      const range = applyColours(mode);
      render();
      if (window.fppViewer) { window.fppViewer.colourBy = mode; window.fppViewer.range = range; }
      return range;
    }

    return { show: show, recolour: recolour, hasQuality: () => !!(cloud && cloud.columns.quality) };
  }

  return { create: create, parsePly: parsePly, MAX_POINTS: MAX_POINTS };
})();
