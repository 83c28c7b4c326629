// The SiTAR Kotlin library as a standalone Gradle build (or include ":sitar"
// from an app's settings with projectDir = file("<repo>/android")).
pluginManagement {
    repositories {
        google()
        mavenCentral()
        gradlePluginPortal()
    }
}
dependencyResolutionManagement {
    repositories {
        google()
        mavenCentral()
    }
}
rootProject.name = "sitar"
