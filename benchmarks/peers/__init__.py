"""Peer implementations of the lightgear equations, used only by the benchmarks."""
