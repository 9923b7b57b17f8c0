"""Tests mirror the package (tests/crf/ for crfmap.crf, ...); the naive references stay here, importable from all."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
