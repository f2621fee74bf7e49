"""Evaluation against the reference: metrics per region, one frame compared, flicker over
time, labelled strips and plots."""
