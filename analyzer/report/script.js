// Draws the report's plots from the JSON in <script id="report-data">; Chart.js is inlined above,
// plots_check.js below.
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("report-data").textContent);
  var start = data.start;
  var COLORS = {
    pitch: "#1f77b4", yaw: "#ff7f0e", motor: "#9467bd",
    pan: "#ff7f0e", tilt: "#1f77b4", feedback: "#2ca02c", errors: "#d62728",
    altitude: "#17becf", track: "#1f77b4",
    obeyed: "#2ca02c", partial: "#ff9800", not_obeyed: "#d62728", unknown: "#888888"
  };

  function clock(seconds) {
    var t = start + seconds;
    if (start < 1e8) { return t.toFixed(1) + " s"; }
    return new Date(t * 1000).toISOString().substring(11, 19) + "Z";
  }

  function points(rows, column) {
    return rows.map(function (r) { return { x: r[0], y: r[column] }; });
  }

  // Dashed vertical lines at the commands' times, with their names when few enough.
  var commandMarks = {
    id: "commandMarks",
    afterDatasetsDraw: function (chart, args, options) {
      var marks = options.marks;
      if (!marks || !marks.length) { return; }
      var area = chart.chartArea, x = chart.scales.x, ctx = chart.ctx;
      ctx.save();
      ctx.strokeStyle = "rgba(60,60,60,0.35)";
      ctx.fillStyle = "rgba(60,60,60,0.8)";
      ctx.font = "10px sans-serif";
      ctx.setLineDash([3, 3]);
      marks.forEach(function (m) {
        var px = x.getPixelForValue(m[0]);
        if (px < area.left || px > area.right) { return; }
        ctx.beginPath(); ctx.moveTo(px, area.top); ctx.lineTo(px, area.bottom); ctx.stroke();
        if (marks.length <= 40) {
          ctx.save(); ctx.translate(px + 2, area.top + 2); ctx.rotate(Math.PI / 2);
          ctx.fillText(m[1], 0, 0); ctx.restore();
        }
      });
      ctx.restore();
    }
  };

  function timeAxis() {
    return { type: "linear", min: 0, max: data.span, title: { display: true, text: "time (UTC)" },
             ticks: { callback: function (v) { return clock(v); }, maxRotation: 0 } };
  }

  function chart(id, datasets, yTitle, options) {
    var canvas = document.getElementById(id);
    if (!canvas) { return; }
    options = options || {};
    var scales = { x: options.x || timeAxis(), y: { title: { display: true, text: yTitle } } };
    if (options.y) { scales.y = options.y; }
    if (options.y2) { scales.y2 = options.y2; }
    new Chart(canvas, {
      type: "scatter",
      data: { datasets: datasets },
      options: {
        animation: false,
        responsive: true,
        maintainAspectRatio: false,
        parsing: false,
        scales: scales,
        plugins: {
          commandMarks: { marks: options.marks || [] },
          legend: { position: "top" },
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
      plugins: [commandMarks]
    });
  }

  function line(label, pts, color, extra) {
    var set = { label: label, data: pts, showLine: true, borderColor: color,
                backgroundColor: color, pointRadius: 0, borderWidth: 1.5 };
    for (var k in (extra || {})) { set[k] = extra[k]; }
    return set;
  }

  function targets(axes) {
    return Object.keys(COLORS).filter(function (v) {
      return ["obeyed", "partial", "not_obeyed", "unknown"].indexOf(v) >= 0;
    }).map(function (verdict) {
      var pts = data.targets.filter(function (t) {
        return t[2] === verdict && axes.indexOf(t[4]) >= 0;
      }).map(function (t) { return { x: t[0], y: t[1], text: t[3] + " (" + verdict + ")" }; });
      return { label: "target, " + verdict.replace("_", " "), data: pts, showLine: false,
               pointStyle: "crossRot", pointRadius: 7, borderWidth: 2,
               borderColor: COLORS[verdict], backgroundColor: COLORS[verdict] };
    }).filter(function (d) { return d.data.length; });
  }

  var att = data.attitude;
  chart("plot-pitch", [line("pitch", points(att, 1), COLORS.pitch)].concat(targets(["pitch"])),
        "pitch (deg)", { marks: data.marks });
  chart("plot-yaw", [line("yaw from north", points(att, 2), COLORS.yaw),
                     line("yaw motor (from the nose)", points(att, 3), COLORS.motor)]
        .concat(targets(["yaw", "motor_yaw"])), "yaw (deg)", { marks: data.marks });
  chart("plot-rates", [
    line("pan commanded", points(data.commanded, 1), COLORS.pan,
         { borderDash: [6, 3], stepped: "before" }),
    line("pan measured", points(data.measured, 1), COLORS.pan, { pointRadius: 2 }),
    line("tilt commanded", points(data.commanded, 2), COLORS.tilt,
         { borderDash: [6, 3], stepped: "before" }),
    line("tilt measured", points(data.measured, 2), COLORS.tilt, { pointRadius: 2 })
  ], "rate (deg/s)", { marks: data.marks });
  chart("plot-health", [
    line("feedback messages per second", points(data.feedback, 1), COLORS.feedback,
         { stepped: "before" }),
    { label: "diagnostics per second", data: points(data.errors, 1), showLine: false,
      pointStyle: "rectRot", pointRadius: 5, borderColor: COLORS.errors,
      backgroundColor: COLORS.errors, yAxisID: "y2" }
  ], "messages/s", { y: { min: 0, title: { display: true, text: "feedback messages/s" } },
                     y2: { position: "right", min: 0,
                           title: { display: true, text: "diagnostics/s" },
                           grid: { drawOnChartArea: false } } });
  chart("plot-altitude", [line("UAV altitude", points(data.altitude, 1), COLORS.altitude)],
        "altitude (m)");
  chart("plot-track", [line("UAV track", points(data.track, 1), COLORS.track, { pointRadius: 1 })],
        "north (m)", { x: { type: "linear", title: { display: true, text: "east (m)" } } });
})();
