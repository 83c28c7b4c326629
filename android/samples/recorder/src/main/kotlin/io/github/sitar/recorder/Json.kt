package io.github.sitar.recorder

/**
 * A small JSON writer for the library's session config and upload options:
 * objects of string, number and boolean fields, strings escaped as RFC 8259
 * asks (quote, backslash, control characters), so a server URL or a session id
 * can never break the document.
 */
object Json {
    /** `{"k":v,…}` in the order given; values are String, Int, Long, Double or Boolean. */
    fun obj(vararg fields: Pair<String, Any>): String {
        val out = StringBuilder("{")
        for ((i, field) in fields.withIndex()) {
            if (i > 0) out.append(',')
            out.append(quote(field.first)).append(':')
            val v = field.second
            when (v) {
                is String -> out.append(quote(v))
                is Int, is Long, is Boolean -> out.append(v.toString())
                is Double -> {
                    require(!v.isNaN() && !v.isInfinite()) { "JSON has no $v (field ${field.first})" }
                    out.append(v.toString())
                }
                else -> throw IllegalArgumentException("field ${field.first}: ${v.javaClass.name} is not a JSON value")
            }
        }
        return out.append('}').toString()
    }

    /** A JSON string literal. */
    fun quote(s: String): String {
        val out = StringBuilder(s.length + 2).append('"')
        for (c in s) {
            when {
                c == '"' -> out.append("\\\"")
                c == '\\' -> out.append("\\\\")
                c == '\n' -> out.append("\\n")
                c == '\r' -> out.append("\\r")
                c == '\t' -> out.append("\\t")
                c < ' ' || c == '\u2028' || c == '\u2029' -> out.append(String.format("\\u%04x", c - '\u0000'))
                else -> out.append(c)
            }
        }
        return out.append('"').toString()
    }
}
