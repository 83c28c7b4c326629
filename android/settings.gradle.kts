// The SiTAR Kotlin library as a Gradle build of its own, with the playback app
// and the recorder sample. An app that includes only the library
// (include(":sitar"); project(":sitar").projectDir = file("<repo>/android"))
// does not read this file: its own build supplies the plugin versions.
pluginManagement {
    repositories {
        google()
        mavenCentral()
        gradlePluginPortal()
    }
    // Versions for this build on its own; an including build brings its own.
    plugins {
        id("com.android.library") version "8.5.2"
        id("com.android.application") version "8.5.2"
        id("org.jetbrains.kotlin.android") version "1.9.24"
    }
}
dependencyResolutionManagement {
    repositories {
        google()
        mavenCentral()
        // rustls-platform-verifier's Kotlin component (build.gradle.kts): its maintainers
        // publish it as a Maven repository in their Git repository, not on Maven Central.
        maven {
            url = uri("https://github.com/rustls/rustls-platform-verifier/raw/maven-archive/android-release-support/maven/")
            content { includeGroup("rustls") }
        }
    }
}
rootProject.name = "sitar"
// The playback app the backend drives (docs/playback-contract.md).
include(":playback")
// The recorder sample app.
include(":samples:recorder")
