// Draws the comparison's plots from the JSON in <script id="compare-data">: the pitch and the yaw
// motor angle of A (solid) and B (dashed) on one time axis (seconds), the pairs that differ as
// red lines. Chart.js is inlined above, analyzer/report/plots_check.js below.
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("compare-data").textContent);
  var COLORS = { a: "#1f77b4", b: "#ff7f0e", differ: "#d62728" };

  var differLines = {
    id: "differLines",
    afterDatasetsDraw: function (chart) {
      var x = chart.scales.x, area = chart.chartArea, ctx = chart.ctx;
      ctx.save();
      ctx.strokeStyle = COLORS.differ;
      ctx.fillStyle = COLORS.differ;
      ctx.font = "11px system-ui, sans-serif";
      data.differ.forEach(function (mark) {
        if (mark[0] < x.min || mark[0] > x.max) { return; }
        var px = x.getPixelForValue(mark[0]);
        ctx.beginPath();
        ctx.moveTo(px, area.top);
        ctx.lineTo(px, area.bottom);
        ctx.stroke();
        ctx.fillText(mark[1], px + 3, area.top + 11);
      });
      ctx.restore();
    }
  };

  function series(label, rows, column, color, dashed) {
    return {
      label: label, borderColor: color, backgroundColor: color, borderWidth: 1.5,
      pointRadius: 1.5, borderDash: dashed ? [6, 4] : [], spanGaps: false,
      data: rows.map(function (r) { return { x: r[0], y: r[column] }; })
    };
  }

  function chart(id, column, title) {
    var canvas = document.getElementById(id);
    if (!canvas) { return; }
    new Chart(canvas, {
      type: "line",
      data: { datasets: [series("A " + title, data.a, column, COLORS.a, false),
                         series("B " + title, data.b, column, COLORS.b, true)] },
      options: {
        animation: false, responsive: true, maintainAspectRatio: false, parsing: false,
        scales: { x: { type: "linear", title: { display: true, text: "s" } },
                  y: { title: { display: true, text: title + " (deg)" } } },
        plugins: { legend: { position: "top" } }
      },
      plugins: [differLines]
    });
  }

  chart("plot-pitch", 1, "pitch");
  chart("plot-yaw", 2, "yaw motor");
})();
