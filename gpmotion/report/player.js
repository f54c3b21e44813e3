/* gpmotion report: the motion player, the generations film, the curves and tables.
   Reads the JSON in #gpm-data (written by gpmotion.report); draws with three.js
   (every figure in 3-D space: planar ones in the x-z plane seen by an orthographic
   side camera) and uPlot.  window.gpmotion exposes the players (the tests drive them). */
(function () {
  "use strict";
  const DATA = JSON.parse(document.getElementById("gpm-data").textContent);
  const SPEEDS = [0.1, 0.25, 0.5, 1, 2, 4];
  const FIGURE = 0xd9822b, JOINT = 0x9c5a1a, CONTACT = 0xd62728, POLE = 0x555555;

  function bytes(b64) {
    const s = atob(b64), u = new Uint8Array(s.length);
    for (let i = 0; i < s.length; i++) u[i] = s.charCodeAt(i);
    return u;
  }
  const f32 = (b64) => new Float32Array(bytes(b64).buffer);
  function q16(o) {                           // 16-bit positions over their range (encode.q16)
    const v = new Int16Array(bytes(o.q).buffer), out = new Float32Array(v.length);
    for (let i = 0; i < v.length; i++) out[i] = o.lo + (v[i] + 32767) * o.step;
    return out;
  }

  function decode(m) {
    if (m._d) return m._d;
    const d = { dims: m.dims, n: m.n, nseg: m.n_seg, times: f32(m.times), segs: q16(m.segs),
                radii: m.radii, events: m.events || [], phases: m.phases || null };
    if (m.contacts) { d.contacts = q16(m.contacts); d.nc = m.n_contacts; d.touching = bytes(m.touching); }
    if (m.points) { d.points = q16(m.points); d.np = m.point_names.length; }
    if (m.ball) d.ball = { r: m.ball.r, xyz: q16(m.ball.xyz), held: bytes(m.ball.held) };
    m._d = d;
    return d;
  }

  function el(tag, attrs, ...kids) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k === "text") e.textContent = v; else if (k === "html") e.innerHTML = v;
      else e.setAttribute(k, v);
    }
    for (const k of kids) if (k != null) e.appendChild(typeof k === "string" ? document.createTextNode(k) : k);
    return e;
  }
  const fmt = (x, d = 4) => (x === null || x === undefined ? "—" : Number(x).toFixed(d));

  function bounds(d) {                        // over every frame: segments, ball, goal
    const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    const r = Math.max(...d.radii, 0.01);
    for (let i = 0; i < d.segs.length; i += 3)
      for (let k = 0; k < 3; k++) { lo[k] = Math.min(lo[k], d.segs[i + k] - r); hi[k] = Math.max(hi[k], d.segs[i + k] + r); }
    return { lo, hi };
  }

  class Player {
    constructor(panel, root, index) {
      this.panel = panel; this.index = index;
      this.best = panel.motion;
      this.film = (panel.film && panel.film.entries.length) ? panel.film.entries : null;
      this.mode = "best"; this.filmIndex = 0;
      this.t = 0; this.playing = false; this.speed = 1; this.trail = -1; this.dirty = true;
      this.buildDom(root);
      this.buildScene();
      this.setClip(this.best);
      this.fitCamera(decode(this.best));
      this.last = null;
      requestAnimationFrame((now) => this.tick(now));
    }

    // ---------------------------------------------------------------- DOM
    buildDom(root) {
      this.view = el("div", { class: "view" });
      this.hud = el("div", { class: "hud" });
      this.view.appendChild(this.hud);
      root.appendChild(this.view);
      const c = el("div", { class: "controls" });
      this.bPlay = el("button", { title: "play / pause (space)", text: "▶" });
      this.bBack = el("button", { title: "one frame back", text: "|◀" });
      this.bFwd = el("button", { title: "one frame on", text: "▶|" });
      this.scrub = el("input", { type: "range", min: "0", max: "1", step: "0.001", value: "0", "aria-label": "time" });
      this.sSpeed = el("select", { "aria-label": "speed" });
      for (const s of SPEEDS) this.sSpeed.appendChild(el("option", { value: String(s), text: s === 1 ? "1× (real time)" : s + "×" }));
      this.sSpeed.value = "1";
      this.sTrail = el("select", { "aria-label": "trail" });
      this.sTrail.appendChild(el("option", { value: "-1", text: "no trail" }));
      (this.best.point_names || []).forEach((n, k) => this.sTrail.appendChild(el("option", { value: String(k), text: "trail: " + n })));
      c.append(this.bPlay, this.bBack, this.bFwd, this.scrub, this.sSpeed, this.sTrail);
      root.appendChild(c);
      this.timeline = el("div", { class: "timeline" });
      root.appendChild(this.timeline);
      if (this.film) {
        const f = el("div", { class: "controls film" });
        this.cFilm = el("input", { type: "checkbox", id: `film${this.index}` });
        this.sGen = el("input", { type: "range", min: "0", max: String(this.film.length - 1), step: "1", value: "0", "aria-label": "generation" });
        this.bPrevGen = el("button", { title: "previous generation's best", text: "◀ gen" });
        this.bNextGen = el("button", { title: "next generation's best", text: "gen ▶" });
        this.lGen = el("span", { class: "gen" });
        f.append(this.cFilm, el("label", { for: `film${this.index}`, text: "film: the best of every generation" }),
                 this.bPrevGen, this.sGen, this.bNextGen, this.lGen);
        root.appendChild(f);
        this.cFilm.onchange = () => this.setMode(this.cFilm.checked ? "film" : "best");
        this.sGen.oninput = () => this.setFilm(Number(this.sGen.value));
        this.bPrevGen.onclick = () => this.setFilm(this.filmIndex - 1);
        this.bNextGen.onclick = () => this.setFilm(this.filmIndex + 1);
      }
      this.bPlay.onclick = () => (this.playing ? this.pause() : this.play());
      this.bBack.onclick = () => this.step(-1);
      this.bFwd.onclick = () => this.step(1);
      this.scrub.oninput = () => this.seek(Number(this.scrub.value));
      this.sSpeed.onchange = () => { this.speed = Number(this.sSpeed.value); this.dirty = true; };
      this.sTrail.onchange = () => this.setTrail(Number(this.sTrail.value));
      this.view.tabIndex = 0;
      this.view.addEventListener("keydown", (e) => {
        if (e.key === " ") { e.preventDefault(); this.bPlay.onclick(); }
        else if (e.key === "ArrowRight") this.step(1); else if (e.key === "ArrowLeft") this.step(-1);
      });
    }

    // ---------------------------------------------------------------- scene
    buildScene() {
      const d = decode(this.best);
      this.is3d = d.dims === 3;
      const w = this.view.clientWidth || 640, h = this.view.clientHeight || 400;
      const R = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
      R.setPixelRatio(1);
      R.setSize(w, h);
      R.setClearColor(0xeef2f6);
      R.shadowMap.enabled = this.is3d;
      this.view.insertBefore(R.domElement, this.hud);
      this.renderer = R;
      this.scene = new THREE.Scene();
      const b = bounds(d);
      this.box = b;
      const size = Math.max(b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2], 0.3);
      this.size = size;
      if (this.is3d) this.camera = new THREE.PerspectiveCamera(40, w / h, size / 100, size * 60);
      else this.camera = new THREE.OrthographicCamera(-1, 1, 1, -1, -size * 20, size * 20);
      this.camera.up.set(0, 0, 1);
      this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8a7a, this.is3d ? 1.6 : 2.2));
      const sun = new THREE.DirectionalLight(0xffffff, this.is3d ? 1.8 : 0.8);
      const cx = (b.lo[0] + b.hi[0]) / 2, cy = (b.lo[1] + b.hi[1]) / 2;
      sun.position.set(cx + size, cy - size * 0.6, b.hi[2] + size * 2);
      sun.target.position.set(cx, cy, 0);
      this.scene.add(sun, sun.target);
      if (this.is3d) {
        sun.castShadow = true;
        const s = sun.shadow.camera, half = size * 1.5;
        s.left = -half; s.right = half; s.top = half; s.bottom = -half; s.near = size * 0.1; s.far = size * 8;
        sun.shadow.mapSize.set(1024, 1024);
      }
      this.addGround(d, b, size);
      this.addMarkers(this.best);
      this.controls = new THREE.OrbitControls(this.camera, R.domElement);
      this.controls.enableRotate = this.is3d;
      this.controls.screenSpacePanning = true;
      this.controls.addEventListener("change", () => { this.dirty = true; });
      this.figure = new THREE.Group();
      this.scene.add(this.figure);
      this.trailLine = null;
      new ResizeObserver(() => this.resize()).observe(this.view);
    }

    addGround(d, b, size) {
      const gz = this.best.ground_z;
      if (gz === null || gz === undefined) return;
      const cx = (b.lo[0] + b.hi[0]) / 2, cy = (b.lo[1] + b.hi[1]) / 2;
      const span = size * 8;
      if (this.is3d) {
        const plane = new THREE.Mesh(new THREE.PlaneGeometry(span, span),
                                     new THREE.MeshStandardMaterial({ color: 0xdfe3d8, roughness: 1 }));
        plane.position.set(cx, cy, gz);
        plane.receiveShadow = true;
        const grid = new THREE.GridHelper(span, Math.round(span / 0.25), 0x9aa39a, 0xbcc4bc);
        grid.rotation.x = Math.PI / 2;
        grid.position.set(cx, cy, gz + 1e-4);
        this.scene.add(plane, grid);
      } else {
        const slab = new THREE.Mesh(new THREE.BoxGeometry(span, 0.5, size),
                                    new THREE.MeshStandardMaterial({ color: 0xcfc8b8 }));
        slab.position.set(cx, 0.5, gz - size / 2);
        this.scene.add(slab);
      }
    }

    addMarkers(m) {
      const pole = new THREE.MeshStandardMaterial({ color: POLE });
      const mk = (p) => {
        const g = new THREE.Group();
        const len = this.is3d ? 1.2 : 0.4;
        const bar = new THREE.Mesh(new THREE.CylinderGeometry(p[2], p[2], len, 24), pole);
        bar.position.set(p[0], 0, p[1]);          // CylinderGeometry's axis is y: the bar runs along y
        bar.castShadow = true;
        g.add(bar);
        const gz = m.ground_z;
        if (this.is3d && gz !== null && gz !== undefined && p[1] > gz) {
          for (const y of [-len / 2, len / 2]) {
            const post = new THREE.Mesh(new THREE.CylinderGeometry(0.01, 0.01, p[1] - gz, 8), pole);
            post.rotation.x = Math.PI / 2;
            post.position.set(p[0], y, (p[1] + gz) / 2);
            post.castShadow = true;
            g.add(post);
          }
        }
        this.scene.add(g);
        return g;
      };
      (m.poles || []).forEach(mk);
      this.phasePoles = (m.phases || []).map((ph) => (ph.poles || []).map(mk));
      if (m.goal) {
        const g = new THREE.Mesh(new THREE.OctahedronGeometry(Math.max(0.02, this.size / 40)),
                                 new THREE.MeshStandardMaterial({ color: 0xf2c200, emissive: 0x554400 }));
        g.position.set(...m.goal);
        this.scene.add(g);
      }
    }

    setClip(m) {
      const d = decode(m);
      this.clip = m; this.d = d;
      for (const c of [...this.figure.children]) { this.figure.remove(c); c.geometry && c.geometry.dispose(); }
      const mat = new THREE.MeshStandardMaterial({ color: FIGURE, roughness: 0.6 });
      this.caps = [];
      for (let s = 0; s < d.nseg; s++) {
        const a = this.end(d, 0, s, 0), b = this.end(d, 0, s, 1);
        const len = a.distanceTo(b);
        const geo = len > 1e-6 ? new THREE.CapsuleGeometry(d.radii[s], len, 6, 16)
                               : new THREE.SphereGeometry(Math.max(d.radii[s], 0.005), 16, 12);
        const mesh = new THREE.Mesh(geo, mat);
        mesh.castShadow = true;
        this.figure.add(mesh);
        this.caps.push(mesh);
      }
      this.dots = [];
      if (d.contacts) {
        const dm = new THREE.MeshBasicMaterial({ color: CONTACT });
        const r = Math.max(0.008, Math.min(...d.radii) * 0.9);
        for (let c = 0; c < d.nc; c++) { const s = new THREE.Mesh(new THREE.SphereGeometry(r, 10, 8), dm); this.figure.add(s); this.dots.push(s); }
      }
      this.ball = null;
      if (d.ball) {
        this.ball = new THREE.Mesh(new THREE.SphereGeometry(d.ball.r, 24, 16), new THREE.MeshStandardMaterial({ color: 0x2a7ab8 }));
        this.ball.castShadow = true;
        this.figure.add(this.ball);
      }
      this.scrub.max = String(d.times[d.n - 1]);
      this.scrub.step = String(d.n > 1 ? d.times[1] - d.times[0] : 0.01);
      this.setTrail(this.trail);
      this.drawTimeline(d);
      this.dirty = true;
    }

    end(d, f, s, k) {
      const i = ((f * d.nseg + s) * 2 + k) * 3;
      return new THREE.Vector3(d.segs[i], d.segs[i + 1], d.segs[i + 2]);
    }

    drawTimeline(d) {
      this.timeline.textContent = "";
      const T = d.times[d.n - 1] || 1;
      for (const ph of d.phases || [])
        this.timeline.appendChild(el("span", { style: `left:${(100 * ph.from / T).toFixed(2)}%;width:${(100 * (ph.to - ph.from) / T).toFixed(2)}%`, title: `${ph.name}: ${ph.from.toFixed(2)}–${ph.to.toFixed(2)} s`, text: ph.name }));
    }

    setTrail(k) {
      this.trail = k;
      if (this.trailLine) { this.scene.remove(this.trailLine); this.trailLine.geometry.dispose(); this.trailLine = null; }
      const d = this.d;
      if (k < 0 || !d.points || k >= d.np) { this.dirty = true; return; }
      const pos = new Float32Array(d.n * 3);
      for (let f = 0; f < d.n; f++) for (let j = 0; j < 3; j++) pos[f * 3 + j] = d.points[(f * d.np + k) * 3 + j];
      const g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.BufferAttribute(pos, 3));
      this.trailLine = new THREE.Line(g, new THREE.LineBasicMaterial({ color: 0x1f5fbf }));
      this.scene.add(this.trailLine);
      this.dirty = true;
    }

    fitCamera(d) {
      const b = this.box, c = new THREE.Vector3((b.lo[0] + b.hi[0]) / 2, (b.lo[1] + b.hi[1]) / 2, (b.lo[2] + b.hi[2]) / 2);
      this.controls.target.copy(c);
      if (this.is3d) {
        const v = this.best.view || {};
        const el_ = (v.elev ?? 22) * Math.PI / 180, az = (v.azim ?? -60) * Math.PI / 180;
        const dist = this.size * 1.9;
        this.camera.position.set(c.x + dist * Math.cos(el_) * Math.cos(az), c.y + dist * Math.cos(el_) * Math.sin(az), c.z + dist * Math.sin(el_));
      } else {
        this.camera.position.set(c.x, c.y - this.size * 5, c.z);
        this.frame2d = { cx: c.x, cz: c.z, w: (b.hi[0] - b.lo[0]) * 1.15 + 0.05, h: (b.hi[2] - b.lo[2]) * 1.15 + 0.05 };
      }
      this.camera.lookAt(c);
      this.resize();
      this.controls.update();
    }

    resize() {
      const w = this.view.clientWidth || 640, h = this.view.clientHeight || 400;
      this.renderer.setSize(w, h);
      if (this.is3d) this.camera.aspect = w / h;
      else if (this.frame2d) {
        const f = this.frame2d, half = Math.max(f.w / 2, (f.h / 2) * w / h);
        const cam = this.camera;
        cam.left = -half; cam.right = half; cam.top = half * h / w; cam.bottom = -half * h / w;
      }
      this.camera.updateProjectionMatrix();
      this.dirty = true;
    }

    // ---------------------------------------------------------------- time
    frameAt(t) {
      const ts = this.d.times;
      let lo = 0, hi = this.d.n - 1;
      if (t >= ts[hi]) return hi;
      while (lo < hi) { const mid = (lo + hi + 1) >> 1; if (ts[mid] <= t + 1e-6) lo = mid; else hi = mid - 1; }
      return lo;
    }
    seek(t) { this.t = Math.max(0, Math.min(t, this.d.times[this.d.n - 1])); this.dirty = true; this.draw(); }
    step(k) { this.pause(); const f = Math.max(0, Math.min(this.d.n - 1, this.frameAt(this.t) + k)); this.seek(this.d.times[f]); }
    play() { this.playing = true; this.last = null; this.bPlay.textContent = "❚❚"; }
    pause() { this.playing = false; this.bPlay.textContent = "▶"; }
    setSpeed(s) { this.speed = s; this.sSpeed.value = String(s); }
    setMode(mode) {
      if (mode === "film" && !this.film) throw new Error("this run has no film of its generations");
      this.mode = mode;
      if (this.cFilm) this.cFilm.checked = mode === "film";
      this.setClip(mode === "film" ? this.film[this.filmIndex].motion : this.best);
      this.seek(0);
      if (this.onFilm) this.onFilm(this);
    }
    setFilm(k) {
      if (!this.film) return;
      this.filmIndex = Math.max(0, Math.min(this.film.length - 1, k));
      this.sGen.value = String(this.filmIndex);
      if (this.mode !== "film") this.mode = "film";
      if (this.cFilm) this.cFilm.checked = true;
      this.setClip(this.film[this.filmIndex].motion);
      this.seek(0);
      if (this.onFilm) this.onFilm(this);
    }

    tick(now) {
      if (this.playing && this.last !== null) {
        this.t += (now - this.last) / 1000 * this.speed;
        const end = this.d.times[this.d.n - 1];
        if (this.t > end) {
          if (this.mode === "film") this.setFilm((this.filmIndex + 1) % this.film.length);
          else this.t = 0;
        }
        this.dirty = true;
      }
      this.last = now;
      if (this.dirty) this.draw();
      requestAnimationFrame((n) => this.tick(n));
    }

    // ---------------------------------------------------------------- drawing
    draw() {
      const d = this.d, f = this.frameAt(this.t);
      this.frame = f;
      const up = new THREE.Vector3(0, 1, 0);
      for (let s = 0; s < d.nseg; s++) {
        const a = this.end(d, f, s, 0), b = this.end(d, f, s, 1);
        const mesh = this.caps[s];
        mesh.position.copy(a).add(b).multiplyScalar(0.5);
        const dir = b.sub(a);
        if (dir.lengthSq() > 1e-12) mesh.quaternion.setFromUnitVectors(up, dir.normalize());
      }
      for (let c = 0; c < this.dots.length; c++) {
        const i = (f * d.nc + c) * 3;
        this.dots[c].position.set(d.contacts[i], d.contacts[i + 1] - (this.is3d ? 0 : 0.05), d.contacts[i + 2]);
        this.dots[c].visible = d.touching[f * d.nc + c] > 0;
      }
      if (this.ball) {
        this.ball.position.set(d.ball.xyz[f * 3], d.ball.xyz[f * 3 + 1], d.ball.xyz[f * 3 + 2]);
        this.ball.material.color.setHex(d.ball.held[f] ? 0x2ca02c : 0x2a7ab8);
      }
      if (this.trailLine) this.trailLine.geometry.setDrawRange(0, f + 1);
      const tNow = d.times[f];
      (d.phases || []).forEach((ph, k) => { for (const g of this.phasePoles[k] || []) g.visible = tNow >= ph.from && tNow <= ph.to; });
      this.scrub.value = String(this.t);
      this.hud.textContent = this.caption(f);
      if (this.controls) this.controls.update();
      this.renderer.render(this.scene, this.camera);
      this.dirty = false;
    }

    caption(f) {
      const d = this.d, lines = [];
      lines.push(`t ${d.times[f].toFixed(2)} s  frame ${f + 1}/${d.n}  ${this.speed === 1 ? "real time" : this.speed + "× real time"}`);
      const ph = (d.phases || []).find((p) => d.times[f] >= p.from && d.times[f] <= p.to);
      if (ph) lines.push(`phase: ${ph.name}`);
      const ev = d.events.filter((e) => Math.abs(e[0] - d.times[f]) < 1e-6).map((e) => e[1]);
      if (ev.length) lines.push(ev.join(", "));
      if (this.mode === "film") {
        const e = this.film[this.filmIndex];
        lines.push(`generation ${e.generation} (${this.filmIndex + 1}/${this.film.length})  cost ${fmt(e.cost)} then, ${fmt(e.cost_final)} final weights`);
      } else if (this.panel.cost !== undefined) lines.push(`best controller  cost ${fmt(this.panel.cost)} (final weights)`);
      if (this.clip.diverged_at !== null && this.clip.diverged_at !== undefined) lines.push(`diverged at ${this.clip.diverged_at.toFixed(2)} s`);
      return lines.join("\n");
    }

    // ---------------------------------------------------------------- for tests and scripts
    state() {
      const e = this.mode === "film" ? this.film[this.filmIndex] : null;
      return { t: this.t, frame: this.frame, time: this.d.times[this.frame], n: this.d.n, playing: this.playing,
               mode: this.mode, film_index: this.filmIndex, film_length: this.film ? this.film.length : 0,
               generation: e ? e.generation : null, cost: e ? e.cost_final : this.panel.cost, dims: this.d.dims,
               camera: this.camera.position.toArray() };
    }
    points() {                                  // the drawn capsules' ends (from the meshes), in the data's coordinates
      const out = [], up = new THREE.Vector3(0, 1, 0);
      for (const m of this.caps) {
        const half = (m.geometry.parameters.length || 0) / 2;
        const axis = up.clone().applyQuaternion(m.quaternion).multiplyScalar(half);
        const ends = [m.position.clone().sub(axis), m.position.clone().add(axis)];
        out.push(ends.map((p) => (this.d.dims === 3 ? [p.x, p.y, p.z] : [p.x, p.z])));
      }
      return out;
    }
    project() {                                 // each segment's midpoint on the page (CSS pixels)
      const r = this.renderer.domElement.getBoundingClientRect(), out = [];
      for (const m of this.caps) {
        const p = m.position.clone().project(this.camera);
        out.push([r.left + (p.x + 1) / 2 * r.width, r.top + (1 - p.y) / 2 * r.height]);
      }
      return out;
    }
  }

  // -------------------------------------------------------------------- curves
  function plotCurves(box, c, width, marker) {
    if (!c || !c.series || !c.series.length) return null;
    const data = [c.x, ...c.series.map((s) => s.y)];
    const opts = {
      width, height: 260, scales: { x: { time: false } },
      series: [{ label: c.xlabel }, ...c.series.map((s) => ({ label: s.label, stroke: s.color, width: s.dash ? 1 : 2, dash: s.dash ? [5, 4] : undefined, spanGaps: false }))],
      axes: [{ label: c.xlabel }, { label: c.ylabel || "cost (lower is better)" }],
      hooks: {
        drawClear: [(u) => {
          const ctx = u.ctx;
          ctx.save(); ctx.fillStyle = "rgba(255,140,0,0.10)";
          for (const w of c.windows || []) {
            const x0 = u.valToPos(w.from, "x", true), x1 = u.valToPos(w.to, "x", true);
            ctx.fillRect(x0, u.bbox.top, Math.max(1, x1 - x0), u.bbox.height);
          }
          ctx.restore();
        }],
        draw: [(u) => {
          if (!marker || marker.x === null) return;
          const ctx = u.ctx, x = u.valToPos(marker.x, "x", true);
          ctx.save(); ctx.strokeStyle = "#d62728"; ctx.lineWidth = 2; ctx.beginPath();
          ctx.moveTo(x, u.bbox.top); ctx.lineTo(x, u.bbox.top + u.bbox.height); ctx.stroke(); ctx.restore();
        }],
      },
    };
    const wrap = el("div", { class: "curve" });
    box.appendChild(wrap);
    const u = new uPlot(opts, data, wrap);
    if ((c.windows || []).length)
      box.appendChild(el("p", { class: "facts", text: "shaded: style terms phasing in — " + c.windows.map((w) => `${w.label} (${c.xlabel} ${w.from.toFixed(0)}–${w.to.toFixed(0)})`).join("; ") }));
    return u;
  }

  function table(t) {
    const tb = el("table");
    tb.appendChild(el("tr", {}, ...t.head.map((h) => el("th", { text: h }))));
    for (const r of t.rows) tb.appendChild(el("tr", {}, ...r.map((v) => el("td", { text: String(v) }))));
    return tb;
  }

  function termsTable(terms) {
    return table({ head: ["term", "value", "weight", "phase", "contribution"],
                   rows: terms.map((r) => [r.term + (r.main ? " (main)" : ""), fmt(r.value), fmt(r.weight, 3), fmt(r.phase, 2), fmt(r.contribution)]) });
  }

  // -------------------------------------------------------------------- page
  function buildPanel(p, i, parent) {
    const box = el("section", { class: "panel", id: `panel${i}` });
    parent.appendChild(box);
    box.appendChild(el("h2", { text: p.name }));
    const head = [p.task, p.family && `controller ${p.family}`, p.actuation && `actuation ${p.actuation}`,
                  p.cost !== undefined && p.cost !== null && `cost ${fmt(p.cost)} (final weights)`,
                  p.solved !== undefined && (p.solved ? "solved" : "not solved")].filter(Boolean);
    box.appendChild(el("p", { class: "facts", text: head.join(" · ") + ((p.facts || []).length ? " — " + p.facts.join("; ") : "") }));
    const player = new Player(p, box, i);
    if (p.film_note) box.appendChild(el("p", { class: "note", text: p.film_note }));
    if (p.film && p.film.of > p.film.entries.length)
      box.appendChild(el("p", { class: "note", text: `film: ${p.film.entries.length} of the ${p.film.of} recorded generations (evenly spread, to keep the page small)` }));
    if (p.curves) {
      box.appendChild(el("h3", { text: "learning curves" }));
      const marker = { x: null };
      const u = plotCurves(box, p.curves, Math.min(900, box.clientWidth - 30 || 600), marker);
      player.onFilm = (pl) => { marker.x = pl.mode === "film" ? pl.film[pl.filmIndex].generation : null; if (u) u.redraw(false, false); };
    }
    if (p.table) { box.appendChild(el("h3", { text: p.table.caption || "" })); box.appendChild(table(p.table)); }
    if (p.terms && p.terms.length) { box.appendChild(el("h3", { text: "the score's terms (final weights)" })); box.appendChild(termsTable(p.terms)); }
    if (p.controller) {
      const s = el("div", { class: "structure" });
      s.appendChild(el("h3", { text: p.controller.caption }));
      if (p.controller.kind === "image") s.appendChild(el("img", { src: "data:image/png;base64," + p.controller.png, alt: p.controller.caption }));
      else if (p.controller.kind === "table") s.appendChild(table(p.controller));
      box.appendChild(s);
    }
    return player;
  }

  function build() {
    const main = document.getElementById("gpm-main");
    document.getElementById("gpm-sub").textContent = DATA.subtitle || "";
    for (const n of DATA.notes || []) main.appendChild(el("p", { class: "note", text: n }));
    if (DATA.table) { main.appendChild(el("h3", { text: DATA.table.caption || "" })); main.appendChild(table(DATA.table)); }
    if (DATA.curves) { main.appendChild(el("h3", { text: DATA.curves.title || "learning curves" })); plotCurves(main, DATA.curves, Math.min(1000, main.clientWidth - 20 || 800), null); }
    const panels = el("div", { class: "panels" });
    main.appendChild(panels);
    const players = DATA.panels.map((p, i) => buildPanel(p, i, panels));
    window.gpmotion = { players, data: DATA, ready: true };
  }
  build();
})();
