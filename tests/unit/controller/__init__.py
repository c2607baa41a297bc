"""Tests of uavtest.controller (a package so test module names cannot clash with other areas)."""
