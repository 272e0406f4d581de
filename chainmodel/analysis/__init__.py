"""Analysis tools on top of the models: run summaries, the multiple-scales perturbation analysis
of seed 004, speed/accuracy trade-off studies and parameter sweeps."""
