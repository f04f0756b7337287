// Runs after a page's plots are drawn (the report's and the fleet report's), for checks:
// how many painted pixels and data points each plot has (a blank canvas has none), and its
// x and y axes: range, plot-area size in pixels, and the ticks as [value, label]; and the
// size each picture decoded to.
(function () {
  "use strict";
  Array.prototype.forEach.call(document.querySelectorAll("canvas"), function (canvas) {
    var ctx = canvas.getContext("2d");
    var pixels = ctx.getImageData(0, 0, canvas.width, canvas.height).data;
    var painted = 0;
    for (var i = 3; i < pixels.length; i += 4 * 7) { if (pixels[i]) { painted++; } }
    canvas.setAttribute("data-painted", String(painted));
    var drawn = Chart.getChart(canvas);
    var count = 0;
    if (drawn) {
      drawn.data.datasets.forEach(function (d) {
        count += d.data.filter(function (v) { return v !== null; }).length;
      });
    }
    canvas.setAttribute("data-points", String(count));
    if (drawn && drawn.scales.x && drawn.scales.y) {
      var axes = {};
      ["x", "y"].forEach(function (id) {
        var scale = drawn.scales[id];
        axes[id] = { min: scale.min, max: scale.max,
                     pixels: id === "x" ? scale.width : scale.height,
                     ticks: scale.ticks.map(function (t) { return [t.value, t.label]; }) };
      });
      axes.points = [];
      drawn.data.datasets.forEach(function (d) {
        d.data.forEach(function (v) { if (v !== null) { axes.points.push([v.x, v.y]); } });
      });
      if (axes.points.length > 5000) { axes.points = []; }  // only small plots list theirs
      canvas.setAttribute("data-axes", JSON.stringify(axes));
    }
  });
  // each picture's decoded size ("0x0" for one that did not decode)
  Array.prototype.forEach.call(document.querySelectorAll("img"), function (img) {
    img.setAttribute("data-shown", img.naturalWidth + "x" + img.naturalHeight);
  });
  document.body.setAttribute("data-plots-ready", "yes");
  // milliseconds from the start of loading the page to its plots drawn
  document.body.setAttribute("data-drawn-ms", String(Math.round(performance.now())));
})();
