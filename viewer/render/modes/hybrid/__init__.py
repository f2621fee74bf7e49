"""The hybrid mode: the ray mask (mask), the CPU ray reveal and its shading (reveal, with
its compiled loops in reveal_kernels), the composite (composite), their parameters
(params) and the pipeline that registers the mode (pipeline). Imports nothing itself, so
a module that needs only the parameters does not load the mode."""
