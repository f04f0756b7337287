"""The flight report: one self-contained HTML file with plots, findings and diagnostics."""
