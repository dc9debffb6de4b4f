"""floret-animate: Interpolate floret key poses (thesis ch. 2.3) into one .floret file per frame."""
