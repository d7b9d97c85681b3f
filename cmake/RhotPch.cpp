// The precompiled headers of cmake/RhotPch.cmake are built with this unit; it has no code of its own.
