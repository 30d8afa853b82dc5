"""The parallel machinery: who owns which columns and which halo copies each rank keeps, and how the bytes move."""
