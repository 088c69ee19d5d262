"""Presentation: figures, reports, progress bars, VTK files and renders."""
