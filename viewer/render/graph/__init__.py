"""The render-graph framework: passes and pipelines, the resource pool, frames, host
resources, state kept across frames, the mode registry, parameters, shaders, timers and
sub-exposure steps. Knows no particular pass or mode."""
