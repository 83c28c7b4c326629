/* bionic's crtend_so.o adds nothing a shared library needs here (its .note.GNU-stack
 * marker, which clang puts in every object); it exists because clang's driver links it
 * after the library's objects for an Android target. Written for scripts/check-android. */
typedef int sitar_crtend_so_is_empty;
