// Draws the report's plots from the JSON in <script id="report-data">; Chart.js is inlined above,
// plots_check.js below. Each series is embedded at a fine level (the samples holding every
// minimum and maximum per time bucket, or every sample of a short flight); the view shows at
// most VIEW_BUCKETS buckets of it, re-bucketed when the user zooms (drag across a time plot;
// double-click or "whole flight" to go back; the page's address keeps the zoom: #zoom=a,b).
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("report-data").textContent);
  var start = data.start;
  var startMs = Math.round(start * 1000);
  var absolute = start >= 1e8;
  var VIEW_BUCKETS = 800;
  var STEPS = [0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 15, 30, 60,
               120, 300, 600, 900, 1800, 3600, 7200, 10800, 21600, 43200, 86400];
  var COLORS = {
    pitch: "#1f77b4", yaw: "#ff7f0e", motor: "#9467bd",
    pan: "#ff7f0e", tilt: "#1f77b4", feedback: "#2ca02c", errors: "#d62728",
    altitude: "#17becf", track: "#1f77b4",
    obeyed: "#2ca02c", partial: "#ff9800", not_obeyed: "#d62728", unknown: "#888888"
  };
  var timeCharts = [];
  var whole = { lo: 0, hi: data.span > 0 ? data.span : 1 };
  var shown = { lo: whole.lo, hi: whole.hi };

  // The exact time of a point: UTC to the millisecond, never rounded to the second.
  function clock(seconds) {
    if (!absolute) { return (start + seconds).toFixed(3).replace(/\.?0+$/, "") + " s"; }
    var ms = startMs + Math.round(seconds * 1000);
    var text = new Date(ms).toISOString().substring(11, 23);
    return text.replace(/\.000$/, "") + "Z";
  }

  // Ticks at round times of day (whole seconds, minutes...), not round offsets from the start.
  function timeTicks(scale) {
    var span = scale.max - scale.min;
    var most = Math.max(3, Math.floor(scale.width / 110));
    var step = STEPS[STEPS.length - 1];
    for (var i = 0; i < STEPS.length; i++) {
      if (span / STEPS[i] <= most) { step = STEPS[i]; break; }
    }
    var stepMs = Math.round(step * 1000);
    var origin = startMs;  // round times of the clock, whatever the first sample's time
    var first = Math.ceil((origin + scale.min * 1000 - 1e-6) / stepMs);
    var ticks = [];
    for (var k = first; (k * stepMs - origin) / 1000 <= scale.max + 1e-9; k++) {
      ticks.push({ value: (k * stepMs - origin) / 1000 });
    }
    scale.ticks = ticks;
  }

  function lowerBound(rows, t) {
    var lo = 0, hi = rows.length;
    while (lo < hi) { var mid = (lo + hi) >> 1; if (rows[mid][0] < t) { lo = mid + 1; } else { hi = mid; } }
    return lo;
  }

  // The rows of one column between lo and hi as points, at most two per bucket of the view
  // (the minimum and the maximum, in time order), with one row either side to join the line.
  function view(rows, column, lo, hi) {
    var i = Math.max(0, lowerBound(rows, lo) - 1);
    var j = Math.min(rows.length, lowerBound(rows, hi) + 1);
    var out = [];
    if (j - i <= 2 * VIEW_BUCKETS) {
      for (var k = i; k < j; k++) { out.push({ x: rows[k][0], y: rows[k][column] }); }
      return out;
    }
    var width = (hi - lo) / VIEW_BUCKETS, bucket = null, low = null, high = null;
    function flush() {
      if (low === null) { return; }
      if (low === high) { out.push({ x: low[0], y: low[column] }); return; }
      var a = low[0] <= high[0] ? low : high, b = a === low ? high : low;
      out.push({ x: a[0], y: a[column] }, { x: b[0], y: b[column] });
    }
    for (var n = i; n < j; n++) {
      var row = rows[n], key = Math.floor((row[0] - lo) / width);
      if (key !== bucket) { flush(); bucket = key; low = high = row; continue; }
      if (row[column] < low[column]) { low = row; }
      if (row[column] > high[column]) { high = row; }
    }
    flush();
    return out;
  }

  // Dashed vertical lines at the commands' times, with their names when few enough show.
  var commandMarks = {
    id: "commandMarks",
    afterDatasetsDraw: function (chart, args, options) {
      var marks = options.marks;
      if (!marks || !marks.length) { return; }
      var area = chart.chartArea, x = chart.scales.x, ctx = chart.ctx;
      var visible = marks.filter(function (m) { return m[0] >= x.min && m[0] <= x.max; });
      ctx.save();
      ctx.strokeStyle = "rgba(60,60,60,0.35)";
      ctx.fillStyle = "rgba(60,60,60,0.8)";
      ctx.font = "10px sans-serif";
      ctx.setLineDash([3, 3]);
      var labelled = -Infinity;  // a label only where it does not overlap the last one
      visible.forEach(function (m) {
        var px = x.getPixelForValue(m[0]);
        ctx.beginPath(); ctx.moveTo(px, area.top); ctx.lineTo(px, area.bottom); ctx.stroke();
        if (visible.length <= 40 && px - labelled >= 11) {
          labelled = px;
          ctx.save(); ctx.translate(px + 2, area.top + 2); ctx.rotate(Math.PI / 2);
          ctx.fillText(m[1], 0, 0); ctx.restore();
        }
      });
      ctx.restore();
    }
  };

  function timeAxis() {
    return { type: "linear", min: shown.lo, max: shown.hi, bounds: "data",
             title: { display: true, text: absolute ? "time (UTC)" : "time" },
             afterBuildTicks: timeTicks,
             ticks: { callback: function (v) { return clock(v); }, maxRotation: 0,
                      autoSkip: false } };
  }

  function chart(id, datasets, yTitle, options) {
    var canvas = document.getElementById(id);
    if (!canvas) { return null; }
    options = options || {};
    var scales = { x: options.x || timeAxis(), y: { title: { display: true, text: yTitle } } };
    if (options.y) { scales.y = options.y; }
    if (options.y2) { scales.y2 = options.y2; }
    var made = new Chart(canvas, {
      type: "scatter",
      data: { datasets: datasets },
      options: {
        animation: false,
        responsive: true,
        maintainAspectRatio: false,
        parsing: false,
        layout: options.layout || {},
        scales: scales,
        plugins: {
          commandMarks: { marks: options.marks || [] },
          legend: { display: options.legend !== false, position: "top" },
          tooltip: {
            callbacks: {
              title: function (items) {
                return items.length && !options.x ? clock(items[0].parsed.x) : "";
              },
              label: function (item) {
                var raw = item.raw;
                if (raw && raw.text) { return raw.text; }
                return item.dataset.label + ": " + item.parsed.y.toFixed(2);
              }
            }
          }
        }
      },
      plugins: [commandMarks].concat(options.plugins || [])
    });
    if (!options.x) { timeCharts.push(made); dragToZoom(made); }
    return made;
  }

  // A line of one column of a series; its points follow the zoom.
  function line(label, rows, column, color, extra) {
    var set = { label: label, data: view(rows, column, shown.lo, shown.hi), showLine: true,
                borderColor: color, backgroundColor: color, pointRadius: 0, borderWidth: 1.5,
                series: rows, column: column };
    for (var k in (extra || {})) { set[k] = extra[k]; }
    return set;
  }

  function zoom(lo, hi) {
    lo = Math.max(whole.lo, lo); hi = Math.min(whole.hi, hi);
    if (!(hi > lo)) { lo = whole.lo; hi = whole.hi; }
    shown.lo = lo; shown.hi = hi;
    timeCharts.forEach(function (c) {
      c.options.scales.x.min = lo; c.options.scales.x.max = hi;
      c.data.datasets.forEach(function (d) {
        if (d.series) { d.data = view(d.series, d.column, lo, hi); }
      });
      c.update("none");
    });
    var zoomed = lo > whole.lo || hi < whole.hi;
    var reset = document.getElementById("zoom-reset");
    if (reset) { reset.hidden = !zoomed; }
    var where = window.location.pathname + window.location.search;
    if (zoomed) { where += "#zoom=" + lo.toFixed(3) + "," + hi.toFixed(3); }
    try { history.replaceState(null, "", where); } catch (e) { /* an address it may not set */ }
    document.body.setAttribute("data-zoom", lo.toFixed(3) + "," + hi.toFixed(3));
  }

  function dragToZoom(c) {
    var canvas = c.canvas, box = document.createElement("div"), from = null;
    box.className = "zoom-box"; box.hidden = true;
    canvas.parentNode.appendChild(box);
    function px(event) { return event.clientX - canvas.getBoundingClientRect().left; }
    canvas.addEventListener("mousedown", function (event) { from = px(event); });
    canvas.addEventListener("mousemove", function (event) {
      if (from === null) { return; }
      var to = px(event), area = c.chartArea;
      box.hidden = false;
      box.style.left = Math.max(area.left, Math.min(from, to)) + "px";
      box.style.width = Math.abs(to - from) + "px";
      box.style.top = area.top + "px"; box.style.height = (area.bottom - area.top) + "px";
    });
    window.addEventListener("mouseup", function (event) {
      if (from === null) { return; }
      var to = px(event), x = c.scales.x;
      box.hidden = true;
      if (Math.abs(to - from) > 4) {
        zoom(x.getValueForPixel(Math.min(from, to)), x.getValueForPixel(Math.max(from, to)));
      }
      from = null;
    });
    canvas.addEventListener("dblclick", function () { zoom(whole.lo, whole.hi); });
  }

  function targets(axes) {
    return ["obeyed", "partial", "not_obeyed", "unknown"].map(function (verdict) {
      var pts = data.targets.filter(function (t) {
        return t[2] === verdict && axes.indexOf(t[4]) >= 0;
      }).map(function (t) { return { x: t[0], y: t[1], text: t[3] + " (" + verdict + ")" }; });
      return { label: "target, " + verdict.replace("_", " "), data: pts, showLine: false,
               pointStyle: "crossRot", pointRadius: 7, borderWidth: 2,
               borderColor: COLORS[verdict], backgroundColor: COLORS[verdict] };
    }).filter(function (d) { return d.data.length; });
  }

  // Equal scale on both axes of the track, every point inside: the ranges are widened to the
  // plot area's proportions, measured after each layout.
  function squareRanges(scale) {
    var b = data.track_bounds, c = scale.chart, area = c.chartArea;
    if (!b) { return; }
    var w = area && area.right > area.left ? area.right - area.left : c.width - 70;
    var h = area && area.bottom > area.top ? area.bottom - area.top : c.height - 50;
    var dx = Math.max(b[1] - b[0], 1), dy = Math.max(b[3] - b[2], 1);
    var perPx = Math.max(dx / w, dy / h) * 1.08;
    var mid = scale.axis === "x" ? (b[0] + b[1]) / 2 : (b[2] + b[3]) / 2;
    var half = perPx * (scale.axis === "x" ? w : h) / 2;
    scale.min = mid - half; scale.max = mid + half;
  }
  // Round distances (1, 2 or 5 times a power of ten) inside the widened range.
  function metreTicks(scale) {
    var span = scale.max - scale.min, most = Math.max(3, Math.floor(scale.width / 80));
    if (scale.axis === "y") { most = Math.max(3, Math.floor(scale.height / 50)); }
    var power = Math.pow(10, Math.floor(Math.log10(span / most))), step = power;
    [1, 2, 5, 10].some(function (m) { step = m * power; return span / step <= most; });
    var ticks = [];
    for (var v = Math.ceil(scale.min / step) * step; v <= scale.max; v += step) {
      ticks.push({ value: Math.round(v / step) * step });
    }
    scale.ticks = ticks;
  }
  var keepSquare = {  // a resize changes the plot area: the ranges follow within a pass or two
    id: "keepSquare",
    afterRender: function (c) {
      var area = c.chartArea, x = c.scales.x, y = c.scales.y;
      var ratio = ((x.max - x.min) / (area.right - area.left)) /
                  ((y.max - y.min) / (area.bottom - area.top));
      if (Math.abs(ratio - 1) <= 0.002) { c.$squarePasses = 0; return; }
      c.$squarePasses = (c.$squarePasses || 0) + 1;
      if (c.$squarePasses <= 3) { c.update("none"); } else { c.$squarePasses = 0; }
    }
  };

  var att = data.attitude;
  chart("plot-pitch", [line("pitch", att, 1, COLORS.pitch)].concat(targets(["pitch"])),
        "pitch (deg)", { marks: data.marks });
  chart("plot-yaw", [line("yaw from north", att, 2, COLORS.yaw),
                     line("yaw motor (from the nose)", att, 3, COLORS.motor)]
        .concat(targets(["yaw", "motor_yaw"])), "yaw (deg)", { marks: data.marks });
  chart("plot-rates", [
    line("pan commanded", data.commanded, 1, COLORS.pan,
         { borderDash: [6, 3], stepped: "before" }),
    line("pan measured", data.measured, 1, COLORS.pan, { pointRadius: 2 }),
    line("tilt commanded", data.commanded, 2, COLORS.tilt,
         { borderDash: [6, 3], stepped: "before" }),
    line("tilt measured", data.measured, 2, COLORS.tilt, { pointRadius: 2 })
  ], "rate (deg/s)", { marks: data.marks });
  chart("plot-health", [
    line("feedback messages per second", data.feedback, 1, COLORS.feedback,
         { stepped: "before" }),
    line("diagnostics per second", data.errors, 1, COLORS.errors,
         { showLine: false, pointStyle: "rectRot", pointRadius: 5, yAxisID: "y2" })
  ], "messages/s", { y: { min: 0, title: { display: true, text: "feedback messages/s" } },
                     y2: { position: "right", min: 0,
                           title: { display: true, text: "diagnostics/s" },
                           grid: { drawOnChartArea: false } } });
  chart("plot-altitude", [line("UAV altitude", data.altitude, 1, COLORS.altitude)],
        "altitude (m)");
  var track = data.track.map(function (r) { return { x: r[0], y: r[1] }; });
  chart("plot-track", [{ label: "UAV track", data: track, showLine: true, pointRadius: 1,
                         borderColor: COLORS.track, backgroundColor: COLORS.track,
                         borderWidth: 1.5 }],
        "north (m)", {
          x: { type: "linear", bounds: "data", afterDataLimits: squareRanges,
               afterBuildTicks: metreTicks, title: { display: true, text: "east (m)" } },
          y: { type: "linear", bounds: "data", afterDataLimits: squareRanges,
               afterBuildTicks: metreTicks, title: { display: true, text: "north (m)" } },
          legend: false, plugins: [keepSquare] });

  var reset = document.getElementById("zoom-reset");
  if (reset) { reset.addEventListener("click", function () { zoom(whole.lo, whole.hi); }); }
  var asked = /#zoom=([-0-9.]+),([-0-9.]+)/.exec(window.location.hash);
  if (asked) { zoom(parseFloat(asked[1]), parseFloat(asked[2])); }
  else { document.body.setAttribute("data-zoom", whole.lo.toFixed(3) + "," + whole.hi.toFixed(3)); }
})();
