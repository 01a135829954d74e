//! Reports: plots (SVG via plotters, PNG pictures) and the HTML/Markdown report.
