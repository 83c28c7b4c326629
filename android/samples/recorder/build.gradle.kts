// The SiTAR recorder sample app: Start/Stop, ARCore's Recording API, depth,
// upload, results drawn over the camera image. Set SERVER_URL in
// RecorderActivity.kt, then (in android/): ./gradlew :samples:recorder:installDebug
plugins {
    id("com.android.application")
    id("org.jetbrains.kotlin.android")
}

android {
    namespace = "io.github.sitar.recorder"
    compileSdk = 34

    defaultConfig {
        applicationId = "io.github.sitar.recorder"
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
    implementation(project(":"))
    implementation("com.google.ar:core:1.44.0")
}
