"""Figures: the paper's theory curves (:mod:`analogue.plots.paper_theory`) drawn on matplotlib
Axes, so that simulated or measured data can be overlaid on them."""
