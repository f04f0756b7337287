// Draws the fleet report's plots from the JSON in <script id="fleet-data">; Chart.js is inlined above,
// analyzer/report/plots_check.js below.
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("fleet-data").textContent);
  var PALETTE = ["#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2",
                 "#17becf", "#bcbd22", "#7f7f7f", "#d62728"];
  var VERDICT_COLORS = { obeyed: "#2ca02c", partial: "#ff9800", not_obeyed: "#d62728",
                         unknown: "#888888" };

  function chart(id, type, labels, datasets, yTitle, stacked) {
    var canvas = document.getElementById(id);
    if (!canvas) { return; }
    new Chart(canvas, {
      type: type,
      data: { labels: labels, datasets: datasets },
      options: {
        animation: false, responsive: true, maintainAspectRatio: false,
        scales: { x: { stacked: !!stacked },
                  y: { stacked: !!stacked, beginAtZero: true,
                       title: { display: true, text: yTitle } } },
        plugins: { legend: { position: "top" } }
      }
    });
  }

  // series: {name: {label: value}} over the shared labels, one dataset per name.
  function sets(series, labels, type) {
    return Object.keys(series).map(function (name, i) {
      var color = VERDICT_COLORS[name] || PALETTE[i % PALETTE.length];
      return { label: name.replace("_", " "), type: type,
               data: labels.map(function (l) { var v = series[name][l]; return v === undefined ? null : v; }),
               borderColor: color, backgroundColor: color, spanGaps: true, pointRadius: 3 };
    });
  }

  chart("plot-crc-week", "line", data.weeks, sets(data.crc_week, data.weeks, "line"),
        "CRC error rate (errors per CRC-checked message)");
  chart("plot-gaps", "bar", data.tag_values, sets(data.gaps, data.tag_values, "bar"),
        "feedback gaps over 1 s");
  chart("plot-verdicts", "bar", data.commands, sets(data.verdicts, data.commands, "bar"),
        "findings", true);
  chart("plot-response", "bar", data.commands, sets(data.response, data.commands, "bar"),
        "median response time (s)");
})();
