// The 3D motion player's animation, in the browser (evomotion studio, studio/nao3d.py).
//
// The server sends a motion's recorded body poses once (float32 [frames, bodies, 7]: position
// x y z, quaternion x y z w, base64) and this loop moves NiceGUI's ui.scene groups itself at
// every animation frame, interpolating between recorded frames (linear positions, slerped
// rotations): no websocket message per frame, so playback is as fast as the browser renders.
// Controls: play/pause, frame stepping, a scrub slider, speed (slow motion), the time.
// cfg.ghost: a second motion's poses (its own translucent groups) on the same clock.
// window.evoPlayers[sceneId] holds each player's state ("applied" counts the poses set,
// "tracks" the motions shown).
(function () {
  if (window.evoStartPlayer) return;
  window.evoPlayers = window.evoPlayers || {};

  function decode(b64) {
    const bin = atob(b64);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Float32Array(bytes.buffer);
  }

  // one recorded motion's body groups: their meshes, poses and scratch quaternions
  function track(comp, spec) {
    const meshes = spec.groups.map((g) => comp.objects.get(g)?.mesh);
    if (meshes.some((m) => !m)) return null;
    return { meshes, f: decode(spec.data), n: spec.nframe, nb: spec.groups.length,
             qa: meshes.map((m) => m.quaternion.clone()),
             qb: meshes.map((m) => m.quaternion.clone()) };
  }

  // the track's bodies at time t (s): frames interpolated; after its end, its last frame
  function place(tr, t, dt) {
    const { meshes, f, n, nb, qa, qb } = tr;
    const x = Math.min(Math.max(t / dt, 0), n - 1);
    const k = Math.floor(x), k1 = Math.min(k + 1, n - 1), a = x - k;
    for (let b = 0; b < nb; b++) {
      const i = (k * nb + b) * 7, j = (k1 * nb + b) * 7;
      meshes[b].position.set(f[i] + a * (f[j] - f[i]), f[i + 1] + a * (f[j + 1] - f[i + 1]),
                             f[i + 2] + a * (f[j + 2] - f[i + 2]));
      qa[b].set(f[i + 3], f[i + 4], f[i + 5], f[i + 6]);
      qb[b].set(f[j + 3], f[j + 4], f[j + 5], f[j + 6]);
      meshes[b].quaternion.slerpQuaternions(qa[b], qb[b], a);
    }
  }

  window.evoStartPlayer = function (cfg, tries) {
    tries = tries || 0;
    const comp = getElement(cfg.scene);
    const specs = cfg.ghost ? [cfg, cfg.ghost] : [cfg];
    const tracks = comp && comp.objects ? specs.map((s) => track(comp, s)) : [null];
    if (!comp || tracks.some((t) => !t)) {
      if (tries < 200) setTimeout(() => window.evoStartPlayer(cfg, tries + 1), 50);
      return;
    }
    const root = document.getElementById(cfg.controls);
    const q = (sel) => root.querySelector(sel);
    const n = Math.max(...tracks.map((t) => t.n));
    const st = { playing: true, speed: 1, t: 0, last: performance.now(), applied: 0, comp,
                 duration: cfg.duration, tracks: tracks.length };
    window.evoPlayers[cfg.scene] = st;

    // a cursor on each analysis chart at the playing time
    const cursors = (cfg.charts || []).map((id) => {
      const el = document.createElement("div");
      el.className = "nao-cursor";
      el.style.cssText = "position:absolute;left:0;top:30px;bottom:30px;width:2px;" +
        "background:#e53935;pointer-events:none;z-index:5;will-change:transform";
      const c = getElement(id);
      if (c && c.$el) { c.$el.style.position = "relative"; c.$el.appendChild(el); }
      return { id, el };
    });
    function moveCursors(t) {
      for (const c of cursors) {
        const chart = getElement(c.id)?.chart;
        const x = chart ? Math.round(chart.convertToPixel({ xAxisIndex: 0 }, t)) : null;
        if (x != null && isFinite(x) && x !== c.x) {  // moved: a compositor-only transform
          c.x = x;
          c.el.style.transform = `translateX(${x - 1}px)`;
        }
      }
    }

    function apply(t) {
      const x = Math.min(Math.max(t / cfg.dt, 0), n - 1);
      for (const tr of tracks) place(tr, t, cfg.dt);
      st.applied++;
      q(".nao-time").textContent =
        `t = ${t.toFixed(2).padStart(5)} s / ${cfg.duration.toFixed(2)} s`;
      if (!st.dragging) q(".nao-scrub").value = String(Math.round(x));
      moveCursors(t);
    }

    function loop(now) {
      if (getElement(cfg.scene) !== comp) {  // the player was removed
        delete window.evoPlayers[cfg.scene];
        return;
      }
      const wall = (now - st.last) / 1000;
      st.last = now;
      if (st.playing) st.t = (st.t + wall * st.speed) % cfg.duration;
      apply(st.t);
      // render here, once per animation frame: NiceGUI's own loop renders one frame in two
      // (an animation frame, then a timeout) and runs at its low "fps" prop beside this one
      comp.camera_tween?.update();
      comp.renderer.render(comp.scene, comp.camera);
      requestAnimationFrame(loop);
    }

    function setPlaying(on) {
      st.playing = on;
      q(".nao-play").textContent = on ? "pause" : "play";
    }
    function stepBy(frames) {
      setPlaying(false);
      const k = Math.round(st.t / cfg.dt) + frames;
      st.t = Math.min(Math.max(k, 0), n - 1) * cfg.dt;
    }
    q(".nao-play").addEventListener("click", () => setPlaying(!st.playing));
    q(".nao-back").addEventListener("click", () => stepBy(-1));
    q(".nao-fwd").addEventListener("click", () => stepBy(1));
    q(".nao-speed").addEventListener("change", (e) => { st.speed = Number(e.target.value); });
    const scrub = q(".nao-scrub");
    scrub.addEventListener("input", () => {
      st.dragging = true;
      setPlaying(false);
      st.t = Number(scrub.value) * cfg.dt;
    });
    scrub.addEventListener("change", () => { st.dragging = false; });
    requestAnimationFrame(loop);
  };
})();
