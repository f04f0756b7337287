// Runs after a page's plots are drawn (the report's and the fleet report's), for checks:
// how many painted pixels and data points each plot has (a blank canvas has none).
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
  });
  document.body.setAttribute("data-plots-ready", "yes");
})();
