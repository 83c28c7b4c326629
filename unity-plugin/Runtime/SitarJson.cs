// A small JSON writer for the session config and upload options: objects of
// string, number and boolean fields, strings escaped as RFC 8259 asks (quote,
// backslash, control characters), so a server URL or a session id can never
// break the document. No UnityEngine dependency (the host test runs it on Mono).
using System;
using System.Globalization;
using System.Text;

namespace Sitar
{
    /// <summary>Builds one JSON object: <c>new SitarJson().Add("k", v).ToString()</c>.</summary>
    public sealed class SitarJson
    {
        private readonly StringBuilder text = new StringBuilder("{");
        private bool empty = true;

        private SitarJson Key(string name)
        {
            if (name == null) throw new ArgumentNullException("name");
            if (!empty) text.Append(',');
            empty = false;
            Quote(text, name);
            text.Append(':');
            return this;
        }

        /// <summary>A string field (escaped); null writes JSON null.</summary>
        public SitarJson Add(string name, string value)
        {
            Key(name);
            if (value == null) text.Append("null");
            else Quote(text, value);
            return this;
        }

        /// <summary>An integer field.</summary>
        public SitarJson Add(string name, long value)
        {
            Key(name).text.Append(value.ToString(CultureInfo.InvariantCulture));
            return this;
        }

        /// <summary>A number field; NaN and infinities have no JSON form and throw.</summary>
        public SitarJson Add(string name, double value)
        {
            if (double.IsNaN(value) || double.IsInfinity(value))
            {
                throw new ArgumentException("JSON has no " + value + " (field " + name + ")", "value");
            }
            Key(name).text.Append(value.ToString("R", CultureInfo.InvariantCulture));
            return this;
        }

        /// <summary>A boolean field.</summary>
        public SitarJson Add(string name, bool value)
        {
            Key(name).text.Append(value ? "true" : "false");
            return this;
        }

        /// <summary>The document.</summary>
        public override string ToString()
        {
            return text.ToString() + "}";
        }

        /// <summary>Appends a JSON string literal.</summary>
        public static void Quote(StringBuilder output, string s)
        {
            output.Append('"');
            foreach (char c in s)
            {
                switch (c)
                {
                    case '"': output.Append("\\\""); break;
                    case '\\': output.Append("\\\\"); break;
                    case '\n': output.Append("\\n"); break;
                    case '\r': output.Append("\\r"); break;
                    case '\t': output.Append("\\t"); break;
                    default:
                        if (c < ' ' || c == '\u2028' || c == '\u2029')
                        {
                            output.Append("\\u").Append(((int)c).ToString("x4", CultureInfo.InvariantCulture));
                        }
                        else
                        {
                            output.Append(c);
                        }
                        break;
                }
            }
            output.Append('"');
        }
    }
}
