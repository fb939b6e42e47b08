#!/usr/bin/env python3
"""Counts the public items of the uq-driver library in rustdoc's all.html (`make lint` runs it
after `cargo doc`) and fails above the budget, so that the public API stays a deliberate one.

usage: api_items.py ALL_HTML BUDGET
"""
import re
import sys

path, budget = sys.argv[1], int(sys.argv[2])
items = re.findall(r'<li><a href="[^"]+">([^<]+)</a></li>', open(path, encoding="utf-8").read())
print(f"uq-driver public API: {len(items)} items in {path} (budget {budget})")
if len(items) > budget:
    print("over budget: make new items pub(crate), or raise the budget on purpose", file=sys.stderr)
    sys.exit(1)
