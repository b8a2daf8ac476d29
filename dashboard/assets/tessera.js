// Tessera dashboard: interactive charts (drawn by the vendored uPlot) and the image viewer.
//
// For: turning the chart specs and image data that the server embeds in each page into canvas
// charts and viewer controls. Not for: data (every number is in the page's HTML tables and
// server-drawn SVG, which stay in place when this script does not run).
(function () {
  'use strict';

  const fmt = v => {
    if (v == null || !isFinite(v)) return '–';
    const a = Math.abs(v);
    if (a === 0) return '0';
    const d = Math.max(0, Math.min(6, 3 - Math.floor(Math.log10(a))));
    return v.toFixed(d);
  };
  const date = s => new Date(s * 1000).toISOString().replace('T', ' ').slice(0, 16) + 'Z';
  const el = (tag, attrs, text) => {
    const e = document.createElement(tag);
    for (const k in attrs || {}) e.setAttribute(k, attrs[k]);
    if (text != null) e.textContent = text;
    return e;
  };
  const alpha = (hex, a) => hex + Math.round(a * 255).toString(16).padStart(2, '0');

  // Wheel zoom around the cursor and shift-drag pan on the x scale; uPlot's own drag selects a
  // range to zoom into and a double click resets.
  function zoomPan(u, fullMin, fullMax) {
    const over = u.over;
    over.addEventListener('wheel', e => {
      e.preventDefault();
      const { min, max } = u.scales.x;
      const at = u.posToVal(e.offsetX, 'x');
      const f = e.deltaY < 0 ? 0.8 : 1.25;
      let lo = at - (at - min) * f, hi = at + (max - at) * f;
      if (hi - lo >= fullMax - fullMin) { lo = fullMin; hi = fullMax; }
      u.setScale('x', { min: lo, max: hi });
    }, { passive: false });
    over.addEventListener('mousedown', e => {
      if (!e.shiftKey) return;
      e.stopPropagation();
      e.preventDefault();
      const x0 = e.clientX, { min, max } = u.scales.x;
      const per = (max - min) / u.bbox.width * devicePixelRatio;
      const move = m => {
        const d = (m.clientX - x0) * per;
        u.setScale('x', { min: min - d, max: max - d });
      };
      const up = () => { document.removeEventListener('mousemove', move); document.removeEventListener('mouseup', up); };
      document.addEventListener('mousemove', move);
      document.addEventListener('mouseup', up);
    }, true);
  }

  // Vertical markers (environment segments in grey, change points in red) on the plot.
  function drawMarkers(u, marks, xOf) {
    const ctx = u.ctx, { top, height } = u.bbox;
    ctx.save();
    for (const m of marks) {
      const x = Math.round(u.valToPos(xOf(m.at), 'x', true));
      if (x < u.bbox.left || x > u.bbox.left + u.bbox.width) continue;
      ctx.strokeStyle = m.kind === 'change' ? '#d62728' : '#999';
      ctx.lineWidth = m.kind === 'change' ? 2 * devicePixelRatio : devicePixelRatio;
      ctx.setLineDash(m.kind === 'change' ? [6, 4] : [2, 3]);
      ctx.beginPath(); ctx.moveTo(x, top); ctx.lineTo(x, top + height); ctx.stroke();
      ctx.fillStyle = ctx.strokeStyle;
      ctx.font = (10 * devicePixelRatio) + 'px sans-serif';
      ctx.fillText(m.short || '', x + 3, top + 12 * devicePixelRatio);
    }
    ctx.restore();
  }

  // A time series chart: spec = {y_label, log, x, commits, runs, series: [{label, color, values,
  // p5, p95}], marks: [{at, kind, label, short}]}.
  function timeChart(box, spec) {
    const n = spec.x.length;
    const positive = spec.series.every(s => s.values.every(v => v == null || v > 0));
    const state = { mode: 'time', log: spec.log && positive };
    const controls = el('div', { class: 'chart-controls' });
    const modeSel = el('select', { 'aria-label': 'x axis' });
    modeSel.append(el('option', { value: 'time' }, 'x: time'), el('option', { value: 'commit' }, 'x: commit'));
    const logBox = el('input', { type: 'checkbox', 'aria-label': 'log scale' });
    logBox.checked = state.log;
    logBox.disabled = !positive;
    const reset = el('button', { type: 'button' }, 'reset zoom');
    const logLabel = el('label', {}, ' log scale ');
    logLabel.prepend(logBox);
    controls.append(modeSel, ' ', logLabel, ' ', reset,
      el('span', { class: 'muted' }, ' drag: zoom · wheel: zoom · shift-drag: pan · double click: all · click: open the run'));
    const plot = el('div', { class: 'chart-plot' });
    const hover = el('div', { class: 'chart-hover' }, '\u00a0');
    let u = null;

    function build() {
      if (u) u.destroy();
      const time = state.mode === 'time';
      const xs = time ? spec.x : spec.x.map((_, i) => i);
      const xOf = i => xs[i];
      const single = xs.length > 0 && xs[0] === xs[xs.length - 1];
      const data = [xs];
      const series = [{ label: time ? 'time' : 'commit', value: (u, v, si, i) => i == null ? '' : spec.commits[i] }];
      const bands = [];
      spec.series.forEach(s => {
        data.push(s.values);
        series.push({ label: s.label, stroke: s.color, width: 1.5, spanGaps: true, points: { show: n <= 300, size: 4, fill: s.color }, value: (u, v) => fmt(v) });
        if (s.p5 && s.p95) {
          const hi = data.length;
          data.push(s.p95, s.p5);
          for (const which of ['p95', 'p5']) {
            series.push({ label: s.label + ' ' + which, stroke: alpha(s.color, 0.35), width: 1, spanGaps: true, points: { show: false }, value: (u, v) => fmt(v) });
          }
          bands.push({ series: [hi, hi + 1], fill: alpha(s.color, 0.15) });
        }
      });
      const width = Math.max(300, box.clientWidth || 900);
      const opts = {
        width, height: 320, series, bands,
        // One point (or several at one time): half a day either side (one commit in commit
        // mode), not uPlot's default span of years.
        scales: { x: single ? { time, auto: false, range: [xs[0] - (time ? 43200 : 1), xs[0] + (time ? 43200 : 1)] } : { time }, y: { distr: state.log ? 3 : 1 } },
        axes: [
          time ? { space: 80 } : { space: 70, incrs: [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000], values: (u, splits) => splits.map(i => spec.commits[Math.round(i)] || '') },
          { label: spec.y_label, size: 70 },
        ],
        cursor: { drag: { x: true, y: false }, points: { size: 7 } },
        legend: { live: true },
        hooks: {
          draw: [u => drawMarkers(u, spec.marks, xOf)],
          setCursor: [u => {
            const i = u.cursor.idx;
            if (i == null) { hover.textContent = '\u00a0'; return; }
            const vals = spec.series.map(s => s.values[i] == null ? null : s.label + ' ' + fmt(s.values[i])).filter(Boolean);
            hover.textContent = 'commit ' + spec.commits[i] + ' · ' + date(spec.x[i]) + ' · run ' + spec.runs[i] + ' · ' + vals.join(' · ');
          }],
        },
      };
      u = new uPlot(opts, data, plot);
      zoomPan(u, xs[0], xs[n - 1]);
      let down = null;
      u.over.addEventListener('mousedown', e => { down = [e.clientX, e.clientY]; });
      u.over.addEventListener('click', e => {
        const i = u.cursor.idx;
        if (!down || Math.abs(e.clientX - down[0]) > 3 || i == null || !spec.runs[i]) return;
        location.href = '/runs/' + encodeURIComponent(spec.runs[i]);
      });
      box.uplot = u;
    }
    modeSel.addEventListener('change', () => { state.mode = modeSel.value; build(); });
    logBox.addEventListener('change', () => { state.log = logBox.checked; build(); });
    reset.addEventListener('click', () => (spec.x[0] === spec.x[n - 1] ? build() : u.setScale('x', { min: u.data[0][0], max: u.data[0][n - 1] })));
    box.replaceChildren(controls, plot, hover);
    build();
    new ResizeObserver(() => { if (u) u.setSize({ width: Math.max(300, box.clientWidth), height: 320 }); }).observe(box);
  }

  // Error against time: spec = {x_label, y_label, log, points: [{x, y, group, num, label, front}],
  // groups: [label, ...]}. Points are numbered as in the table beside the chart; a point with no
  // row there (num null) is drawn without a number.
  function scatterChart(box, spec) {
    const xs = Array.from(new Set(spec.points.map(p => p.x))).sort((a, b) => a - b);
    const at = new Map(xs.map((x, i) => [x, i]));
    const colours = ['#4e79a7', '#aaaaaa'];
    const data = [xs];
    const series = [{ label: spec.x_label, value: (u, v) => fmt(v) }];
    const members = [];
    spec.groups.forEach((g, gi) => {
      const ys = xs.map(() => null);
      const front = xs.map(() => null);
      const who = xs.map(() => []);
      spec.points.filter(p => p.group === gi).forEach(p => {
        const i = at.get(p.x);
        ys[i] = p.y; who[i].push(p);
        if (p.front) front[i] = p.y;
      });
      data.push(ys, front);
      members.push(who);
      const c = colours[gi % colours.length];
      series.push({ label: g, stroke: c, fill: undefined, paths: () => null, points: { show: true, size: 9, width: 2, fill: gi === 0 ? c : '#fff', stroke: c }, value: (u, v) => fmt(v) });
      series.push({ label: g + ' front', stroke: c, width: 1.5, dash: gi === 0 ? undefined : [5, 4], spanGaps: true, points: { show: false }, value: (u, v) => fmt(v) });
    });
    const positive = spec.points.every(p => p.y > 0);
    const state = { log: false };
    const controls = el('div', { class: 'chart-controls' });
    const logBox = el('input', { type: 'checkbox', 'aria-label': 'log scale' });
    logBox.disabled = !positive;
    const logLabel = el('label', {}, ' log scale ');
    logLabel.prepend(logBox);
    const reset = el('button', { type: 'button' }, 'reset zoom');
    controls.append(logLabel, ' ', reset, el('span', { class: 'muted' }, ' drag: zoom · wheel: zoom · shift-drag: pan · numbers: rows of the table'));
    const plot = el('div', { class: 'chart-plot' });
    const hover = el('div', { class: 'chart-hover' }, '\u00a0');
    let u = null;
    const pad = (lo, hi) => { const d = (hi - lo) || Math.abs(hi) || 1; return [lo - d * 0.08, hi + d * 0.08]; };
    const [x0, x1] = pad(xs[0], xs[xs.length - 1]);
    function build() {
      if (u) u.destroy();
      const opts = {
        width: Math.max(300, box.clientWidth || 700), height: 420, series,
        scales: { x: { time: false, range: (u, lo, hi) => pad(lo, hi) }, y: { distr: state.log ? 3 : 1, range: state.log ? undefined : (u, lo, hi) => pad(lo, hi) } },
        axes: [{ label: spec.x_label }, { label: spec.y_label, size: 70 }],
        cursor: { drag: { x: true, y: true, uni: 20 }, points: { size: 11 } },
        // The legend names the runs and their fronts (a click hides one); the values under the
        // cursor are in the hover line, so the legend has none ("run …: –" otherwise).
        legend: { live: false },
        hooks: {
          draw: [u => {
            const ctx = u.ctx;
            ctx.save();
            const d = devicePixelRatio;
            ctx.font = (11 * d) + 'px sans-serif';
            // Each point of the newer run in its technique's colour; its number placed where it
            // overlaps no number already placed (right-up, right-down, left-up, left-down, further out).
            const placed = [];
            const overlaps = (r) => placed.some(q => r.x < q.x + q.w && q.x < r.x + r.w && r.y < q.y + q.h && q.y < r.y + r.h);
            // Error bars where the result has repeats: the GPU time's and the measure's 95% intervals.
            spec.points.filter(p => p.group === 0 && (p.x_interval || p.y_interval)).forEach(p => {
              const px = u.valToPos(p.x, 'x', true), py = u.valToPos(p.y, 'y', true);
              ctx.strokeStyle = p.colour || '#4e79a7';
              ctx.lineWidth = 1.2 * d;
              ctx.beginPath();
              if (p.x_interval) {
                const a = u.valToPos(p.x_interval[0], 'x', true), b = u.valToPos(p.x_interval[1], 'x', true);
                ctx.moveTo(a, py); ctx.lineTo(b, py);
                ctx.moveTo(a, py - 3 * d); ctx.lineTo(a, py + 3 * d); ctx.moveTo(b, py - 3 * d); ctx.lineTo(b, py + 3 * d);
              }
              if (p.y_interval) {
                const a = u.valToPos(p.y_interval[0], 'y', true), b = u.valToPos(p.y_interval[1], 'y', true);
                ctx.moveTo(px, a); ctx.lineTo(px, b);
                ctx.moveTo(px - 3 * d, a); ctx.lineTo(px + 3 * d, a); ctx.moveTo(px - 3 * d, b); ctx.lineTo(px + 3 * d, b);
              }
              ctx.stroke();
            });
            spec.points.filter(p => p.group === 0).forEach(p => {
              const px = u.valToPos(p.x, 'x', true), py = u.valToPos(p.y, 'y', true);
              if (px < u.bbox.left || px > u.bbox.left + u.bbox.width || py < u.bbox.top || py > u.bbox.top + u.bbox.height) return;
              ctx.fillStyle = p.colour || '#4e79a7';
              ctx.beginPath(); ctx.arc(px, py, 4.5 * d, 0, 2 * Math.PI); ctx.fill();
              if (p.num == null) return;
              const text = String(p.num), w = ctx.measureText(text).width, h = 11 * d;
              let spot = null;
              for (const k of [1, 2, 3]) {
                for (const [dx, dy] of [[6, -5], [6, 12], [-6 - w / d, -5], [-6 - w / d, 12], [0, -12], [0, 20]]) {
                  const r = { x: px + dx * d * k, y: py + dy * d * k - h, w, h };
                  if (!overlaps(r)) { spot = r; break; }
                }
                if (spot) break;
              }
              if (!spot) spot = { x: px + 6 * d, y: py - 5 * d - h, w, h };
              placed.push(spot);
              ctx.fillStyle = '#222';
              ctx.fillText(text, spot.x, spot.y + h);
            });
            ctx.restore();
          }],
          setCursor: [u => {
            const i = u.cursor.idx;
            if (i == null) { hover.textContent = '\u00a0'; return; }
            const ps = members.flatMap((who, gi) => who[i].map(p => (p.num == null ? '' : '#' + p.num + ' ') + p.label + ' (' + spec.groups[gi] + '): ' + fmt(p.x) + ' ms, ' + fmt(p.y)));
            hover.textContent = ps.join(' · ') || '\u00a0';
          }],
        },
      };
      u = new uPlot(opts, data, plot);
      zoomPan(u, x0, x1);
      box.uplot = u;
    }
    logBox.addEventListener('change', () => { state.log = logBox.checked; build(); });
    reset.addEventListener('click', () => build());
    box.replaceChildren(controls, plot, hover);
    build();
    new ResizeObserver(() => { if (u) u.setSize({ width: Math.max(300, box.clientWidth), height: 420 }); }).observe(box);
  }

  // The image viewer: panes of one frame (reference, variant, heat map, rate, other run) at a
  // shared zoom with synchronized scrolling; A/B flicker and a wipe between reference and variant;
  // a frame slider with playback. spec = {frames: [n...], kinds: [k...], urls: [[url per kind]
  // per frame], width, height}.
  function viewer(root, spec) {
    const q = s => root.querySelector(s);
    const panes = Array.from(root.querySelectorAll('.pane'));
    const zoom = q('#zoom'), zoomOut = q('#zoomval'), frame = q('#frame'), frameNo = q('#frameno');
    const play = q('#play'), flick = q('#flicker'), wipe = q('#wipe');
    const wipeImg = q('#wipe-top'), abImg = q('#img-ab');
    let cur = 0, showingRef = false, timer = null, userZoom = false;
    // Until the user picks a zoom, small frames open enlarged (whole steps, at most 8x, about
    // 360 px wide) so a 96 px test frame is not a thumbnail; large frames open at natural size.
    // A frame wider than its pane (4K in a half-width pane) opens fitted to the pane, whole.
    function fitZoom() {
      const first = root.querySelector('img.px');
      const w0 = spec.width || (first && first.naturalWidth) || 0;
      if (!w0) return 1;
      const pw = panes.length ? panes[0].clientWidth : 0;
      if (pw > 0 && w0 > pw) return Math.max(1 / 32, pw / w0);
      return Math.max(1, Math.min(8, Math.floor(360 / w0)));
    }
    const url = (f, k) => spec.urls[f][spec.kinds.indexOf(k)] || '';
    function setZoom(z) {
      z = Math.max(Math.min(1, fitZoom()), Math.min(32, z || 0));
      zoom.value = Math.max(1, Math.round(z));
      zoomOut.textContent = z < 1 ? Math.round(z * 100) + '% (fit)' : z + '×';
      root.dataset.zoom = z;
      const first = root.querySelector('img.px');
      const w0 = spec.width || (first && first.naturalWidth) || 0, h0 = spec.height || (first && first.naturalHeight) || 0;
      if (!w0) return;
      root.querySelectorAll('img.px').forEach(i => { i.style.width = w0 * z + 'px'; i.style.height = h0 * z + 'px'; });
      root.querySelectorAll('.stack').forEach(s => { s.style.width = w0 * z + 'px'; s.style.height = h0 * z + 'px'; });
    }
    // The per-frame charts: a marker at the shown frame in each.
    const markers = Array.from(root.querySelectorAll('.frame-chart svg')).map(svg => ({
      line: svg.querySelector('.frame-marker'), f0: +svg.dataset.f0, x0: +svg.dataset.x0, dx: +svg.dataset.dx,
    }));
    function setFrame(f) {
      cur = f;
      frame.value = f;
      frameNo.textContent = spec.frames[f];
      markers.forEach(m => {
        const x = (m.x0 + (spec.frames[f] - m.f0) * m.dx).toFixed(1);
        m.line.setAttribute('x1', x); m.line.setAttribute('x2', x);
      });
      spec.kinds.forEach(k => {
        root.querySelectorAll('img[data-kind="' + k + '"]').forEach(i => { const u = url(f, k); if (u) i.src = u; });
      });
      abImg.src = url(f, showingRef ? 'reference' : 'output') || abImg.src;
    }
    function setAB(ref) {
      showingRef = ref;
      const u = url(cur, ref ? 'reference' : 'output');
      if (u) abImg.src = u;
      q('#ab-label').textContent = ref ? 'A: reference' : 'B: variant';
    }
    function setWipe(p) {
      wipe.value = p;
      // The top image (the reference, A) shows left of the line.
      wipeImg.style.clipPath = 'inset(0 ' + (100 - p) + '% 0 0)';
      q('#wipe-line').style.left = p + '%';
    }
    // Scrolling one pane scrolls the others to the same place.
    let syncing = false;
    panes.forEach(p => p.addEventListener('scroll', () => {
      if (syncing) return;
      syncing = true;
      panes.forEach(o => { if (o !== p) { o.scrollLeft = p.scrollLeft; o.scrollTop = p.scrollTop; } });
      syncing = false;
    }));
    // Dragging a pane pans all of them.
    panes.forEach(p => p.addEventListener('mousedown', e => {
      if (e.button !== 0) return;
      e.preventDefault();
      const x0 = e.clientX, y0 = e.clientY, l = p.scrollLeft, t = p.scrollTop;
      const move = m => { p.scrollLeft = l - (m.clientX - x0); p.scrollTop = t - (m.clientY - y0); };
      const up = () => { document.removeEventListener('mousemove', move); document.removeEventListener('mouseup', up); };
      document.addEventListener('mousemove', move);
      document.addEventListener('mouseup', up);
    }));
    zoom.addEventListener('input', () => { userZoom = true; setZoom(+zoom.value); });
    const fit = q('#fit');
    if (fit) fit.addEventListener('click', () => { userZoom = false; setZoom(fitZoom()); });
    frame.addEventListener('input', () => setFrame(+frame.value));
    wipe.addEventListener('input', () => setWipe(+wipe.value));
    flick.addEventListener('click', () => setAB(!showingRef));
    play.addEventListener('click', () => {
      if (timer) { clearInterval(timer); timer = null; play.textContent = 'play'; return; }
      play.textContent = 'pause';
      timer = setInterval(() => setFrame((cur + 1) % spec.frames.length), 500);
    });
    document.addEventListener('keydown', e => {
      if (e.target.tagName === 'INPUT' && e.target.type !== 'range') return;
      if (e.key === 'f' || e.key === ' ') { e.preventDefault(); setAB(!showingRef); }
      else if (e.key === '+' || e.key === '=') { userZoom = true; setZoom(Math.max(1, (+root.dataset.zoom || 1) * 2)); }
      else if (e.key === '-') { userZoom = true; setZoom(Math.floor((+root.dataset.zoom || 1) / 2)); }
      else if (e.key === 'ArrowRight') setFrame(Math.min(spec.frames.length - 1, cur + 1));
      else if (e.key === 'ArrowLeft') setFrame(Math.max(0, cur - 1));
    });
    root.viewer = { setZoom, setFrame, setWipe, setAB };
    root.querySelectorAll('img.px').forEach(i => i.addEventListener('load', () => setZoom(userZoom ? +zoom.value : fitZoom())));
    setZoom(fitZoom());
    setWipe(+wipe.value);
    // `#f=N` (the run page's worst-frame links) opens at measured frame N when it was saved.
    const asked = /^#f=(\d+)$/.exec(location.hash);
    const at = asked ? spec.frames.indexOf(+asked[1]) : -1;
    setFrame(at >= 0 ? at : 0);
  }

  // Two checked runs in the runs list open the compare page.
  function pickTwo(form) {
    const boxes = Array.from(form.querySelectorAll('input[type=checkbox][name=pick]'));
    const go = form.querySelector('button.compare');
    const update = () => {
      const on = boxes.filter(b => b.checked);
      go.disabled = on.length !== 2;
    };
    boxes.forEach(b => b.addEventListener('change', update));
    go.addEventListener('click', e => {
      e.preventDefault();
      const on = boxes.filter(b => b.checked).map(b => b.value);
      if (on.length === 2) location.href = '/compare/runs?a=' + encodeURIComponent(on[1]) + '&b=' + encodeURIComponent(on[0]);
    });
    update();
  }

  function start() {
    document.querySelectorAll('[data-chart]').forEach(box => {
      const spec = JSON.parse(document.getElementById(box.dataset.chart).textContent);
      if (typeof uPlot === 'undefined') return;
      (spec.kind === 'scatter' ? scatterChart : timeChart)(box, spec);
    });
    document.querySelectorAll('[data-viewer]').forEach(root => {
      viewer(root, JSON.parse(document.getElementById(root.dataset.viewer).textContent));
    });
    document.querySelectorAll('form.pick-two').forEach(pickTwo);
  }
  if (document.readyState === 'loading') document.addEventListener('DOMContentLoaded', start);
  else start();
})();
