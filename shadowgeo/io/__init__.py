"""Readers and writers, one module per format. They know the scene model,
not the shadow algorithms."""
