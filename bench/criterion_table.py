#!/usr/bin/env python3
"""Prints criterion results (median, mean) under target/criterion as a markdown table.

Usage: bench/criterion_table.py GROUP [GROUP...]
"""
import json, pathlib, sys

root = pathlib.Path(__file__).resolve().parent.parent / "target" / "criterion"
print("| benchmark | median | mean |")
print("|---|---|---|")
def fmt(ns):
    return f"{ns/1e6:.2f} ms" if ns >= 1e6 else f"{ns/1e3:.2f} µs" if ns >= 1e3 else f"{ns:.0f} ns"
for group in sys.argv[1:]:
    for est in sorted((root / group).glob("*/new/estimates.json")):
        d = json.loads(est.read_text())
        print(f"| {group}/{est.parent.parent.name} | {fmt(d['median']['point_estimate'])} | {fmt(d['mean']['point_estimate'])} |")
