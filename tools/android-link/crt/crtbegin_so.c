/* What bionic's crtbegin_so.o gives every shared library an NDK links, written anew for
 * scripts/check-android from what AOSP's libc/arch-common/bionic/{crtbegin_so.c,crtbrand.S}
 * define (the NDK ships them compiled):
 * - __dso_handle, the library's identity for __cxa_atexit and __cxa_thread_atexit_impl
 *   (Rust's std names it for thread-local destructors);
 * - __cxa_finalize(&__dso_handle) when the library is unloaded;
 * - the .note.android.ident note with the API level the library was linked for. */
extern void __cxa_finalize(void *);

__attribute__((visibility("hidden"))) void *__dso_handle = &__dso_handle;

__attribute__((visibility("hidden"), destructor)) void __on_dlclose(void) {
    __cxa_finalize(&__dso_handle);
}

#ifndef SITAR_ANDROID_API
#define SITAR_ANDROID_API 24
#endif
#define STR_(x) #x
#define STR(x) STR_(x)
__asm__(".pushsection .note.android.ident,\"a\",%note\n"
        ".balign 4\n"
        ".long 8\n"                  /* name size: "Android\0" */
        ".long 4\n"                  /* descriptor size: the API level */
        ".long 1\n"                  /* NT_ANDROID_TYPE_IDENT */
        ".ascii \"Android\\0\"\n"
        ".long " STR(SITAR_ANDROID_API) "\n"
        ".popsection\n");
