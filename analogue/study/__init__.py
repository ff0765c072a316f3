"""The study layer: what a report compares (the observable catalogue), independent of how the
circuit is run or the page is drawn."""
