package io.github.sitar

import android.content.Context

/** Process-wide setup of the native library. */
object Sitar {
    /**
     * Lets unpinned `https://` uploads (no `server_cert_sha256`) trust what Android trusts:
     * the device's trust store, user and enterprise CAs as the app's network security config
     * allows, and Android's revocation checks (rustls-platform-verifier). Call it once, with
     * any Context (its application Context is kept), before the first upload, e.g. in
     * `Application.onCreate` or the first Activity's `onCreate`; later calls change nothing.
     *
     * Needs the verifier's Kotlin component, the `rustls:rustls-platform-verifier` AAR, in
     * the app (`android/README.md`). Without it, or without this call, the library checks
     * servers against the Mozilla roots bundled in it: a public certificate works, a site CA
     * does not (pin it), and logcat (tag `sitar`) says why.
     *
     * @return true when Android's verifier is in use from now on.
     */
    @JvmStatic
    fun init(context: Context): Boolean = Native.platformTlsInit(context.applicationContext ?: context)
}
