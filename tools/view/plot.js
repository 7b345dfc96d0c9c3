// soadyn view: one plot against time on a canvas, with a cursor (two elements over the canvas, so
// moving it redraws nothing), its axes' titles with their units (elements too, so they can be
// read), and click-or-drag to seek.  Used by viewer.js.
window.SoadynPlot = (function () {
  'use strict';
  function niceTicks(a, b, n) {
    if (!(b > a)) { const d = Math.abs(a) > 0 ? Math.abs(a) * 0.1 : 1; a -= d; b += d; }
    const raw = (b - a) / n, mag = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= raw);
    const lo = Math.floor(a / step) * step, hi = Math.ceil(b / step) * step;
    const ticks = [];
    for (let v = lo; v <= hi + 1e-9 * step; v += step) ticks.push(Math.abs(v) < 1e-9 * step ? 0 : v);
    const big = Math.max.apply(null, ticks.map(Math.abs));
    const exp = big >= 1e4 || big < 1e-3;
    const digits = exp ? Math.max(0, Math.floor(Math.log10(big)) - Math.floor(Math.log10(step)))
                       : Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
    const label = (v) => (v === 0 ? '0' : exp ? v.toExponential(digits) : v.toFixed(digits));
    return { lo: lo, hi: hi, ticks: ticks, label: label };
  }
  // canvas: where to draw; T: the frame times; onSeek(t): a click or drag at time t
  function Plot(canvas, T, onSeek) {
    this.canvas = canvas;
    this.T = T;
    this.ctx = canvas.getContext('2d');
    this.y = null;
    // the cursor: a line and a dot over the canvas, moved without redrawing the plot
    const wrap = document.createElement('div');
    wrap.className = 'plot-wrap';
    canvas.parentNode.insertBefore(wrap, canvas);
    wrap.appendChild(canvas);
    this.line = document.createElement('div');
    this.line.className = 'plot-cursor';
    this.dot = document.createElement('div');
    this.dot.className = 'plot-dot';
    wrap.appendChild(this.line);
    wrap.appendChild(this.dot);
    // the axes' titles: "time (s)" under the plot, the quantity and its unit along its left side
    this.xLabel = document.createElement('div');
    this.xLabel.className = 'plot-axis plot-axis-x';
    this.yLabel = document.createElement('div');
    this.yLabel.className = 'plot-axis plot-axis-y';
    wrap.appendChild(this.xLabel);
    wrap.appendChild(this.yLabel);
    const self = this;
    let dragging = false;
    const seekTo = (e) => {
      const r = canvas.getBoundingClientRect(), x = e.clientX - r.left;
      onSeek(self.x0 + (x - self.left) / self.w * (self.x1 - self.x0));
    };
    canvas.addEventListener('mousedown', (e) => { dragging = true; seekTo(e); });
    window.addEventListener('mousemove', (e) => { if (dragging) seekTo(e); });
    window.addEventListener('mouseup', () => { dragging = false; });
  }
  Plot.prototype.set = function (y) { this.y = y; this.draw(); };
  // the axes' titles, each with its unit: x "time (s)", y e.g. "shoulder (rad)"
  Plot.prototype.setLabels = function (x, y) { this.xLabel.textContent = x; this.yLabel.textContent = y; this.draw(); };
  // this.marks: times drawn as dashed vertical lines (the joint limits' events)
  Plot.prototype.resize = function () {
    const dpr = window.devicePixelRatio || 1;
    this.cw = this.canvas.clientWidth;
    this.ch = this.canvas.clientHeight;
    this.canvas.width = Math.max(1, Math.round(this.cw * dpr));
    this.canvas.height = Math.max(1, Math.round(this.ch * dpr));
    this.draw();
  };
  // axes, ticks and the curve, drawn once (and on resize)
  Plot.prototype.draw = function () {
    if (!this.y || !this.cw) return;
    const dpr = window.devicePixelRatio || 1, c = this.ctx, T = this.T, K = T.length, t0 = T[0], t1 = T[K - 1];
    c.setTransform(dpr, 0, 0, dpr, 0, 0);
    c.clearRect(0, 0, this.cw, this.ch);
    c.font = '10px system-ui, sans-serif';
    let ymin = Infinity, ymax = -Infinity;
    for (let k = 0; k < K; ++k) { const v = this.y[k]; if (isFinite(v)) { ymin = Math.min(ymin, v); ymax = Math.max(ymax, v); } }
    if (!isFinite(ymin)) { ymin = -1; ymax = 1; }
    const yt = niceTicks(ymin, ymax, 4), xt = niceTicks(t0, t1, 5);
    xt.lo = t0; xt.ticks = xt.ticks.filter((v) => v >= t0 - 1e-9 && v <= t1 + 1e-9);
    this.left = 70; this.top = 8; this.w = this.cw - this.left - 10; this.h = this.ch - this.top - 34;
    this.yLabel.style.top = this.top + 'px';
    this.yLabel.style.height = this.h + 'px';
    this.x0 = t0; this.x1 = t1 > t0 ? t1 : t0 + 1; this.y0 = yt.lo; this.y1 = yt.hi;
    c.strokeStyle = '#e3e7ed'; c.fillStyle = '#5b6574'; c.lineWidth = 1;
    c.textAlign = 'right'; c.textBaseline = 'middle';
    yt.ticks.forEach((v) => {
      const py = this.py(v);
      c.beginPath(); c.moveTo(this.left, py); c.lineTo(this.left + this.w, py); c.stroke();
      c.fillText(yt.label(v), this.left - 4, py);
    });
    c.textAlign = 'center'; c.textBaseline = 'top';
    xt.ticks.forEach((v) => {
      const px = this.px(v);
      c.beginPath(); c.moveTo(px, this.top); c.lineTo(px, this.top + this.h); c.stroke();
      c.fillText(xt.label(v), px, this.top + this.h + 4);
    });
    if (this.marks && this.marks.length) {
      c.save(); c.strokeStyle = 'rgba(194, 37, 92, 0.7)'; c.setLineDash([3, 3]); c.beginPath();
      this.marks.forEach((tm) => { const px = this.px(tm); c.moveTo(px, this.top); c.lineTo(px, this.top + this.h); });
      c.stroke(); c.restore();
    }
    c.strokeStyle = '#9aa3ad'; c.strokeRect(this.left, this.top, this.w, this.h);
    c.strokeStyle = '#2f6fb0'; c.lineWidth = 1.3; c.beginPath();
    for (let k = 0; k < K; ++k) {
      const px = this.px(T[k]), py = this.py(this.y[k]);
      if (k === 0) c.moveTo(px, py); else c.lineTo(px, py);
    }
    c.stroke();
    this.line.style.top = this.top + 'px';
    this.line.style.height = this.h + 'px';
  };
  Plot.prototype.px = function (x) { return this.left + (x - this.x0) / (this.x1 - this.x0) * this.w; };
  Plot.prototype.py = function (y) { return this.top + (1 - (y - this.y0) / (this.y1 - this.y0)) * this.h; };
  // the cursor at time t, frame k
  Plot.prototype.cursor = function (t, k) {
    if (!this.y || !this.cw) return;
    this.line.style.transform = 'translateX(' + this.px(t).toFixed(1) + 'px)';
    this.dot.style.transform = 'translate(' + this.px(t).toFixed(1) + 'px,' + this.py(this.y[k]).toFixed(1) + 'px)';
  };
  return Plot;
})();
