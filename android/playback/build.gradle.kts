// The SiTAR playback app (docs/playback-contract.md): `sitar serve --playback adb`
// starts it on every playback phone. Build and install:
//   ./gradlew :playback:installDebug        (in android/)
// then once per phone: adb shell pm grant io.github.sitar.playback android.permission.CAMERA
plugins {
    id("com.android.application")
    id("org.jetbrains.kotlin.android")
}

android {
    // The package is the backend's default --adb-package: change both or neither.
    namespace = "io.github.sitar.playback"
    compileSdk = 34

    defaultConfig {
        applicationId = "io.github.sitar.playback"
        minSdk = 24
        targetSdk = 34
        versionCode = 1
        versionName = "0.1.0"
    }

    compileOptions {
        sourceCompatibility = JavaVersion.VERSION_1_8
        targetCompatibility = JavaVersion.VERSION_1_8
    }
    kotlinOptions {
        jvmTarget = "1.8"
    }
}

dependencies {
    // The SiTAR library module: android/ itself (its libsitar.so comes with it).
    implementation(project(":"))
    implementation("com.google.ar:core:1.44.0")
}
